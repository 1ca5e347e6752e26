//! A continuation from the estimated tip and its check, shared by the replan and every
//! strategy it tries: what a replan is given ([`ReplanInput`]) and returns ([`Replanned`]), the
//! sub-problem a strategy solves from the tip, and the check every continuation passes before it
//! is commanded, which executes its motor steps on the nominal needle (not the optimiser's
//! numbers).

use super::predict::{predict_accepted, Prediction};
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
    let miss = accepted_miss(input);
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

/// The miss a continuation may predict: the target's tolerance, or half of what the smallest
/// turn the dead band allows would move the end, when that is more. Turning the bevel by θ
/// turns the whole continuation about the tip's heading, moving its end by θ times the end's
/// distance from that axis; a turn rounded to the band's steps (none, or the band) misses by at
/// most half a step.
pub(super) fn accepted_miss(input: &ReplanInput) -> f32 {
    let local = input.tip.r.transpose() * (input.target - input.tip.p);
    let off_axis = crate::fmath::sqrt(local.x * local.x + local.y * local.y);
    let step = input.dead_band_deg.to_radians() * off_axis;
    input.scenario.target.tolerance.max(0.5 * step)
}
