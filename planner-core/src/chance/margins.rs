//! The margins each obstacle is grown by: what a round's spread asks of it, capped where the
//! entry or the target would fall inside.

use crate::execute::risk::ObstacleRisk;
use crate::model::scenario::Scenario;
use crate::MAX_OBSTACLES;

use super::upper_quantile;

/// An obstacle whose probability is below this share of the bound gets no share of it.
const NEGLIGIBLE_SHARE: f32 = 0.01;

/// The largest margin obstacle `ob` may take and still leave the entry and the target outside
/// it (nine tenths of the smaller gap): near the target, the bound may be out of reach.
fn margin_cap(scenario: &Scenario, i: usize) -> f32 {
    let Some(ob) = scenario.obstacles.get(i) else {
        return 0.0;
    };
    let gap = |p: [f32; 3]| {
        let d: f32 = (0..3)
            .map(|k| (p[k] - ob.center[k]) * (p[k] - ob.center[k]))
            .sum();
        crate::fmath::sqrt(d) - ob.radius
    };
    0.9 * gap(scenario.entry.position)
        .min(gap(scenario.target.position))
        .max(0.0)
}

/// Raises the margins of the obstacles that matter so that each would keep its share of the
/// bound at the spread just measured. Returns whether any margin grew.
pub(super) fn raise_margins(
    scenario: &Scenario,
    bound: f32,
    by_obstacle: &[ObstacleRisk; MAX_OBSTACLES],
    margins: &mut [f32; MAX_OBSTACLES],
) -> bool {
    let count = scenario.obstacles.len().min(MAX_OBSTACLES);
    let mut matters = [false; MAX_OBSTACLES];
    for i in 0..count {
        matters[i] = by_obstacle[i].probability > NEGLIGIBLE_SHARE * bound || margins[i] > 0.0;
    }
    let active = matters.iter().filter(|m| **m).count().max(1);
    let k = upper_quantile(bound / active as f32);
    let mut raised = false;
    for i in (0..count).filter(|&i| matters[i]) {
        let o = &by_obstacle[i];
        let wanted = (k * o.sd + o.steering_margin).min(margin_cap(scenario, i));
        if wanted > margins[i] + 1e-3 {
            margins[i] = wanted;
            raised = true;
        }
    }
    raised
}
