//! Re-planning the rest of the path from an estimated tip: the same objective and constraints as
//! the global plan (target reached, every clearance above the scenario's floor, the segment
//! bounds), solved by the same SQP from a fixed start, warm-started from what remains of the
//! current continuation, then from a few short forms; and the check every continuation passes
//! before it is commanded, which executes its motor steps on the nominal needle (not the
//! optimiser's numbers).

use super::attempt::attempt;
use super::predict::predict_accepted;
pub use super::predict::{predict, predict_with, Prediction};
use crate::execute::schedule::{continuation_steps, Op, Step, Steps};
use crate::model::form::{Form, SegmentKind, MAX_CONTROL_DEGREE};
use crate::model::kinematics::{Frame, V3};
use crate::model::scenario::{Obstacles, Scenario, Workspace};
use crate::report::{SegmentPlan, Segments};

/// The segments the remaining `steps` drive: each rotation becomes the bevel before the next
/// arc (a spun line keeps the bevel where it is).
pub fn segments_of(steps: &[Step]) -> Option<Segments> {
    let mut out = Segments::new();
    let mut pending = 0.0f32;
    for step in steps {
        let (kind, length) = match step.op {
            Op::Rotate { angle_deg } => {
                pending += angle_deg;
                continue;
            }
            Op::Insert { length_mm } => (SegmentKind::Arc, length_mm),
            Op::InsertDuty { length_mm, duty } if duty > 0.0 => (SegmentKind::Arc, length_mm),
            Op::InsertSpin { length_mm, .. } | Op::InsertDuty { length_mm, .. } => {
                (SegmentKind::Line, length_mm)
            }
        };
        let bevel_deg = if kind == SegmentKind::Arc {
            core::mem::take(&mut pending)
        } else {
            0.0
        };
        out.push(SegmentPlan {
            kind,
            length,
            bevel_deg,
        })
        .ok()?;
    }
    Some(out)
}

/// The form of `segments` (`None` when it is empty, too long or has two lines in a row).
pub fn form_of(segments: &[SegmentPlan]) -> Option<Form> {
    let mut arcs = 0u8;
    for (i, s) in segments.iter().enumerate().take(MAX_CONTROL_DEGREE) {
        if s.kind == SegmentKind::Arc {
            arcs |= 1 << i;
        }
    }
    Form::new(segments.len(), arcs)
}

/// An angle in degrees wrapped to (-180, 180].
pub(super) fn wrapped_deg(rad: f32) -> f32 {
    let mut d = rad.to_degrees() % 360.0;
    if d > 180.0 {
        d -= 360.0;
    } else if d <= -180.0 {
        d += 360.0;
    }
    d
}

/// What a replan needs: the scenario, the estimate, and the budget.
#[derive(Clone, Copy)]
pub struct ReplanInput<'a> {
    /// The planning problem (obstacles, weights, bounds, driver).
    pub scenario: &'a Scenario,
    /// The estimated tip.
    pub tip: Frame,
    /// The estimated target.
    pub target: V3,
    /// Arc radius of the tissue as estimated (mm).
    pub radius: f32,
    /// The shaft's accumulated twist now (degrees).
    pub twist_deg: f32,
    /// SQP iterations per attempt.
    pub iterations: u32,
    /// Clearance kept on top of the scenario's floor for the estimate's uncertainty (mm).
    pub margin: f32,
    /// Needle inserted so far (mm): a continuation inserts at most the rest of its length.
    pub inserted_mm: f32,
    /// Bevel turns smaller than this are left out of a continuation (degrees).
    pub dead_band_deg: f32,
    /// The share of the curvature a continuation's arcs are pushed at (1: plain pushes; below,
    /// duty-cycled, keeping the rest in hand).
    pub arc_duty: f32,
    /// Whether the continuation may spend the curvature the arcs keep in hand (the target
    /// would be missed, or the clearance is at stake); one that only restores the margin keeps
    /// it, and the route.
    pub spend_reserve: bool,
    /// The lab says the tissue's curvature changes along the insertion: this replan tries only
    /// the turn the target needs made first, while the curvature is there
    /// ([`super::early::turned_early`]); refused, the steering tries the rest at the next
    /// reading (one reading's work is one or the other, within the device's budget).
    pub turn_early: bool,
}

/// A continuation that passed the check.
#[derive(Clone, Debug)]
pub struct Replanned {
    /// The motor steps from the tip on.
    pub steps: Steps,
    /// Its check.
    pub prediction: Prediction,
    /// Evaluations spent (all attempts).
    pub evaluations: u32,
    /// SQP iterations spent (all attempts).
    pub iterations: u32,
}

/// The sub-problem's scenario: the tip as entry, the estimated target and tissue, in 3-D. A
/// plane scenario's circles become spheres centred in the tip's plane x = tip.x (the cylinder
/// they stand for, where the path is); the check then measures the true cylinders. Never inlined:
/// built in its caller's place, not copied there.
#[inline(never)]
pub(super) fn sub_scenario(input: &ReplanInput) -> Scenario {
    let from = input.scenario;
    // Field by field, the obstacles pushed in place: a clone passes the list (16 bytes a sphere)
    // through temporaries on the device's stack.
    let mut s = Scenario {
        needle: from.needle,
        entry: from.entry,
        target: from.target,
        obstacles: Obstacles::new(),
        weights: from.weights,
        options: from.options,
        driver: from.driver,
    };
    // Cannot fail: the same capacity.
    let _ = s.obstacles.extend_from_slice(&from.obstacles);
    let t = input.target;
    s.target.position = [t.x, t.y, t.z];
    s.entry.position = [input.tip.p.x, input.tip.p.y, input.tip.p.z];
    let h = input.tip.e3();
    s.entry.direction = [h.x, h.y, h.z];
    s.needle.curvature_radius = input.radius;
    s.options.curvature_reserve = 1.0 - input.arc_duty;
    if s.options.workspace == Workspace::PlaneYz {
        for o in s.obstacles.iter_mut() {
            o.center[0] = input.tip.p.x;
        }
    }
    s.options.workspace = Workspace::Space;
    s.options.min_clearance += input.margin;
    s
}

/// `segments` from the tip as motor steps, if executing them passes the check: the target
/// within tolerance, every clearance above the floor and the margin, the needle's length and
/// the twist limit kept.
#[inline(never)]
pub(super) fn checked(
    input: &ReplanInput,
    segments: &[SegmentPlan],
    spent: &(u32, u32),
) -> Option<Replanned> {
    let (steps, peak) = continuation_steps(
        &input.scenario.driver,
        segments,
        input.twist_deg,
        input.arc_duty,
    )
    .ok()?;
    let length: f32 = segments.iter().map(|s| s.length).sum();
    sound(input, steps, peak, length, spent)
}

/// `steps` (inserting `length` in all, reaching the twist `peak`) if executing them from the tip
/// passes the check.
pub(super) fn sound(
    input: &ReplanInput,
    steps: Steps,
    peak: f32,
    length: f32,
    spent: &(u32, u32),
) -> Option<Replanned> {
    let miss = super::turns::accepted_miss(input);
    sound_within(input, (steps, peak, length), miss, spent)
}

/// [`sound`] with the predicted miss allowed up to `miss` (mm) instead of the tolerance.
pub(super) fn sound_within(
    input: &ReplanInput,
    (steps, peak, length): (Steps, f32, f32),
    miss: f32,
    spent: &(u32, u32),
) -> Option<Replanned> {
    let fits = input.inserted_mm + length <= input.scenario.needle.length
        && peak <= input.scenario.driver.max_twist_deg;
    if !fits {
        return None;
    }
    let floor = input.scenario.options.min_clearance + input.margin;
    let prediction = predict_accepted(
        input.scenario,
        &input.tip,
        &steps,
        input.radius,
        input.target,
        (miss, floor),
    )?;
    Some(Replanned {
        steps,
        prediction,
        evaluations: spent.0,
        iterations: spent.1,
    })
}

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
    use crate::execute::schedule::schedule;

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
