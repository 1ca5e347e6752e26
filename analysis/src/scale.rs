//! Scenarios for the scale bench: many spheres of which a few lie near the entry–target segment,
//! with `planner.risk = "sum"` and `planner.risk_within_mm`, beside the near ones alone. The two
//! must plan alike (the far spheres add nothing to D and take no rows); the bench
//! (`needle bench --near-and-far 256,32`) times them side by side.

use needle_sim::random::{seeded, Draw};
use planner_core::model::scenario::{Obstacle, Obstacles, RiskMeasure, Workspace};
use planner_core::{PlanReport, Scenario};

/// The reach of the risk term, and the most a near sphere's surface lies from the segment (mm).
pub const REACH_MM: f32 = 20.0;

/// The least a far sphere's surface lies from the segment (mm): two and a half reaches, so that the
/// paths the planner tries, which bend away from the chord, stay out of the far spheres' reach.
pub const FAR_GAP_MM: f64 = 50.0;

/// The scenario with every sphere, and the same with its near spheres alone (in the same order).
pub struct NearFar {
    /// `total` spheres.
    pub all: Scenario,
    /// The `near` spheres within [`REACH_MM`] of the segment.
    pub near_alone: Scenario,
}

/// `total` spheres drawn from `seed` (at most `MAX_OBSTACLES`), `near` of them (at random
/// places in the list) with their surface 1 to 18 mm from the entry–target segment and the
/// rest at least [`FAR_GAP_MM`] from it; 3-D, D the sum over the spheres within [`REACH_MM`].
pub fn near_and_far(seed: u64, total: usize, near: usize) -> NearFar {
    let mut base = Scenario::paper();
    base.options.workspace = Workspace::Space;
    base.options.risk = RiskMeasure::Sum;
    base.options.risk_within_mm = Some(REACH_MM);
    base.target.position = [10.0, -6.0, 95.0];
    base.obstacles.clear();
    let mut rng = seeded(seed);
    let entry = [0.0f64; 3];
    let t = base.target.position.map(f64::from);
    let chord = [t[0] - entry[0], t[1] - entry[1], t[2] - entry[2]];
    let len = (chord[0] * chord[0] + chord[1] * chord[1] + chord[2] * chord[2]).sqrt();
    let axis = chord.map(|c| c / len);
    // Two unit vectors across the chord.
    let u = normalised(cross(axis, [1.0, 0.0, 0.0]));
    let v = cross(axis, u);
    // Which places in the list hold the near spheres: a partial shuffle of the indices.
    let mut places: Vec<usize> = (0..total).collect();
    for i in 0..near.min(total) {
        let j = rng.int(i, total - 1);
        places.swap(i, j);
    }
    let near_places = &places[..near.min(total)];
    let mut all = base.clone();
    let mut near_alone = base;
    for i in 0..total {
        let is_near = near_places.contains(&i);
        let (along, radius, gap) = if is_near {
            (
                rng.range(0.15, 0.85),
                rng.range(1.5, 4.5),
                rng.range(1.0, 18.0),
            )
        } else {
            let gap = rng.range(FAR_GAP_MM, 3.0 * FAR_GAP_MM);
            (rng.range(-0.3, 1.3), rng.range(2.0, 8.0), gap)
        };
        let turn = rng.range(0.0, std::f64::consts::TAU);
        let out = radius + gap;
        let center: [f64; 3] = std::array::from_fn(|k| {
            entry[k] + axis[k] * along * len + out * (turn.cos() * u[k] + turn.sin() * v[k])
        });
        let ob = Obstacle {
            center: center.map(|c| c as f32),
            radius: radius as f32,
        };
        push(&mut all.obstacles, ob);
        if is_near {
            push(&mut near_alone.obstacles, ob);
        }
    }
    NearFar { all, near_alone }
}

fn push(list: &mut Obstacles, ob: Obstacle) {
    // The callers stay within the capacity; past it the sphere is left out.
    let _ = list.push(ob);
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalised(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    a.map(|c| c / n)
}

/// Where two reports' plans differ: the forms and, form by form, the insertion and every
/// segment, compared bit for bit (`None` when they are the same plan).
pub fn plan_difference(a: &PlanReport, b: &PlanReport) -> Option<String> {
    if a.forms.len() != b.forms.len() {
        return Some(format!("{} forms against {}", a.forms.len(), b.forms.len()));
    }
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (x, y) in a.forms.iter().zip(&b.forms) {
        let ix = &x.insertion;
        let iy = &y.insertion;
        let same = x.form == y.form
            && x.feasible == y.feasible
            && bits(&[ix.theta1_deg, ix.theta2_deg]) == bits(&[iy.theta1_deg, iy.theta2_deg])
            && x.segments.len() == y.segments.len()
            && x.segments.iter().zip(&y.segments).all(|(s, t)| {
                s.kind == t.kind && bits(&[s.length, s.bevel_deg]) == bits(&[t.length, t.bevel_deg])
            });
        if !same {
            return Some(format!("form {}: {x:?} against {y:?}", x.form));
        }
    }
    match (a.best(), b.best()) {
        (Some(x), Some(y)) if x.form == y.form => None,
        (None, None) => None,
        _ => Some("a different best form".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Surface distance from a sphere to the entry–target segment.
    fn gap(s: &Scenario, ob: &Obstacle) -> f32 {
        let (a, b) = (s.entry.position, s.target.position);
        let ab: [f32; 3] = std::array::from_fn(|k| b[k] - a[k]);
        let ac: [f32; 3] = std::array::from_fn(|k| ob.center[k] - a[k]);
        let dot = |x: &[f32; 3], y: &[f32; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        let t = (dot(&ac, &ab) / dot(&ab, &ab)).clamp(0.0, 1.0);
        let d: [f32; 3] = std::array::from_fn(|k| ac[k] - t * ab[k]);
        dot(&d, &d).sqrt() - ob.radius
    }

    #[test]
    fn the_near_spheres_are_near_and_the_others_far() {
        let NearFar { all, near_alone } = near_and_far(3, 256, 32);
        assert_eq!((all.obstacles.len(), near_alone.obstacles.len()), (256, 32));
        all.validate().unwrap();
        near_alone.validate().unwrap();
        let near: Vec<_> = all
            .obstacles
            .iter()
            .filter(|o| gap(&all, o) < REACH_MM)
            .copied()
            .collect();
        assert_eq!(&near[..], &near_alone.obstacles[..]);
        assert!(all
            .obstacles
            .iter()
            .all(|o| gap(&all, o) < 18.0 + 1e-3 || gap(&all, o) > FAR_GAP_MM as f32 - 1e-3));
        // Not all at the front of the list.
        assert_ne!(&all.obstacles[..32], &near_alone.obstacles[..]);
    }

    #[test]
    fn far_spheres_beyond_the_reach_leave_the_plan_as_it_was() {
        let NearFar {
            mut all,
            mut near_alone,
        } = near_and_far(1, 256, 32);
        let a = planner_core::plan(&all).unwrap();
        let b = planner_core::plan(&near_alone).unwrap();
        assert_eq!(plan_difference(&a, &b), None);
        assert!(a.best().is_some());
        // Without the reach every far sphere weighs 1/d: the plans part.
        all.options.risk_within_mm = None;
        near_alone.options.risk_within_mm = None;
        let a = planner_core::plan(&all).unwrap();
        let b = planner_core::plan(&near_alone).unwrap();
        assert!(plan_difference(&a, &b).is_some());
    }
}
