//! Re-planning the rest of the path from an estimated tip: the same objective and constraints as
//! the global plan (target reached, every clearance above the scenario's floor, the segment
//! bounds), solved by the same SQP from a fixed start, warm-started from what remains of the
//! current continuation, then from a few short forms; then the strategies that aim the bevel
//! directly. Every continuation passes the check of [`super::continuation`] before it is
//! commanded.

use super::attempt::attempt;
use super::continuation::sub_scenario;
pub use super::continuation::{form_of, segments_of, ReplanInput, Replanned};
pub use super::predict::{predict, predict_with, Prediction};
use crate::model::form::{Form, SegmentKind};
use crate::report::{SegmentPlan, Segments};

/// Re-plans from the estimate: told to turn early, the turn made early alone; otherwise the
/// remaining segments (warm start), the same with a degree of freedom more ([`variants`]), the
/// short forms RL, LR and RR aimed at the target, all at the continuation's arc duty; then the
/// turn spent first; the duty-cycled arc aimed through the target; when the arcs keep curvature
/// in hand, the short forms at the full curvature. Returns the continuation (if any passes the
/// check), the evaluations and the iterations spent.
pub fn replan(input: &ReplanInput, remaining: &[SegmentPlan]) -> (Option<Replanned>, u32, u32) {
    let mut spent = (0u32, 0u32);
    if input.turn_early {
        return (super::early::turned_early(input, &spent), 0, 0);
    }
    let found = forms_from(input, remaining, &mut spent)
        .or_else(|| {
            (input.arc_duty < 1.0 && input.spend_reserve)
                .then(|| super::aimed::front_loaded(input, &spent))
                .flatten()
        })
        .or_else(|| super::aimed::aimed_duty(input, &spent))
        .or_else(|| {
            (input.arc_duty < 1.0 && input.spend_reserve)
                .then(|| {
                    let full = ReplanInput {
                        arc_duty: 1.0,
                        spend_reserve: true,
                        ..*input
                    };
                    forms_from(&full, &[], &mut spent)
                })
                .flatten()
        });
    (found, spent.0, spent.1)
}

/// The forms tried from the tip (see [`replan`]), the first that passes the check.
fn forms_from(
    input: &ReplanInput,
    remaining: &[SegmentPlan],
    spent: &mut (u32, u32),
) -> Option<Replanned> {
    let mut sub = sub_scenario(input);
    // Aim the bevel at the target, across the heading.
    let local = input.tip.r.transpose() * (input.target - input.tip.p);
    let bevel_deg = crate::fmath::atan2(-local.x, local.y).to_degrees();
    let [a, b, c] = super::warm::variants(remaining, bevel_deg);
    let warm = [
        Segments::from_slice(remaining).ok(),
        a,
        b,
        c,
        super::warm::turned_away(input, remaining),
    ];
    for start in warm.iter().flatten() {
        let Some(form) = form_of(start) else {
            continue;
        };
        if let Some(r) = attempt(input, &mut sub, form, start, spent) {
            return Some(r);
        }
    }
    let radius = sub.planned_radius();
    let ahead = local.z.max(1.0);
    let sideways = crate::fmath::sqrt(local.x * local.x + local.y * local.y);
    let turn = crate::fmath::atan2(2.0 * sideways, ahead);
    let arc = (turn * radius).max(0.5);
    let seg = |kind, length, bevel_deg| SegmentPlan {
        kind,
        length,
        bevel_deg,
    };
    let line = (ahead - 0.5 * arc).max(0.5);
    let short = [
        (
            "RL",
            [
                seg(SegmentKind::Arc, arc, bevel_deg),
                seg(SegmentKind::Line, line, 0.0),
            ],
        ),
        (
            "LR",
            [
                seg(SegmentKind::Line, line, 0.0),
                seg(SegmentKind::Arc, arc, bevel_deg),
            ],
        ),
        (
            "RR",
            [
                seg(SegmentKind::Arc, arc, bevel_deg),
                seg(SegmentKind::Arc, arc, 180.0),
            ],
        ),
    ];
    for (word, start) in short {
        let Some(form) = Form::parse(word) else {
            continue;
        };
        if let Some(r) = attempt(input, &mut sub, form, &start, spent) {
            return Some(r);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::nominal::posture_frame;
    use crate::execute::schedule::{schedule, Op};
    use crate::model::kinematics::V3;
    use crate::model::scenario::{Scenario, Workspace};

    #[test]
    fn a_rolled_tip_is_steered_back_onto_the_target() {
        let mut scenario = Scenario::paper();
        scenario.options.workspace = Workspace::Space;
        let best = crate::plan(&scenario).unwrap().best().unwrap().clone();
        let s = schedule(&scenario, &best).unwrap();
        let r = scenario.needle.curvature_radius;
        let tip = posture_frame(&scenario, &s)
            .advanced(SegmentKind::Arc, 12.0, r)
            .rolled(3f32.to_radians());
        let mut remaining = Segments::new();
        for (i, seg) in best.segments.iter().enumerate() {
            let mut seg = *seg;
            seg.bevel_deg = 0.0;
            if i == 0 {
                seg.length -= 12.0;
            }
            remaining.push(seg).unwrap();
        }
        let t = scenario.target.position;
        let input = ReplanInput {
            scenario: &scenario,
            tip,
            target: V3::new(t[0], t[1], t[2]),
            radius: r,
            twist_deg: 0.0,
            iterations: 10,
            margin: 0.3,
            inserted_mm: 0.0,
            dead_band_deg: 0.0,
            arc_duty: 1.0,
            spend_reserve: true,
            turn_early: false,
        };
        let (found, evaluations, iterations) = replan(&input, &remaining);
        let found = found.expect("a continuation");
        std::println!(
            "{evaluations} evaluations, {iterations} iterations: {:?}",
            found.steps
        );
        assert!(found.prediction.target_error <= scenario.target.tolerance);
        assert!(matches!(found.steps[0].op, Op::Rotate { .. }));
    }
}
