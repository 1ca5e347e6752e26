//! The turn made early, while the plan's share of the curvature still reaches. In layered
//! tissue the estimate learns a softer layer only after bending in it, and an arc that keeps its
//! reserve to the end meets a softer layer late with the turn still to make (space-clinical,
//! seed 688: a layer at 0.43 from 68 mm learnt by 77 mm, 2.5 mm still to the side 22 mm before
//! the target). Curvature a layer offers at one depth cannot be saved for another, so the turn
//! the target needs is made while the curvature is there: what is left after it needs less, and
//! a later layer that bends less takes less away.

use super::aimed::{aimed_bevels, aimed_tries, front_loaded, heading_turn};
use super::continuation::{ReplanInput, Replanned};
use crate::execute::schedule::{duty_continuation, duty_step};
use crate::model::kinematics::V3;
use crate::model::scenario::Workspace;

/// How much wider than the steering's margin a turn made early keeps from the obstacles: it is
/// taken while the plan still reaches, so it may ask for more room than a continuation that must
/// be taken (3 standard deviations of the tip's position, not 2). Chosen on space-clinical and
/// the planted family 201-220 (1: three collisions in 1000 space runs where 1.5 leaves one,
/// that of the plan): docs/execution.md, "Layers ahead: the turn made early".
pub(super) const EARLY_TURN_MARGIN: f32 = 1.5;

/// Rounding slack when the arc after part of the turn meets the plan's share.
const DUTY_SLACK: f32 = 1e-3;

/// The turn made early, if it keeps [`EARLY_TURN_MARGIN`] times the margin: the whole of it
/// first (the full estimated curvature until the needle heads at the target, then a spun line:
/// [`front_loaded`]); refused, the largest share of it that the obstacles leave, at the full
/// curvature, followed by the arc through the target ([`part_then_arc`]), as long as that arc
/// needs no more than the plan's share. A plan keeping nothing in hand has no early turn.
///
/// Why part of the turn rather than all of it at less curvature: the curvature spent now is
/// what a softer layer ahead cannot take away, and part of the turn at the full curvature spends
/// more of it sooner. Where a sphere lies on the line to the target (space-clinical's first
/// sphere sits on the line from entry to target), the whole turn's line meets it, while part of
/// the turn and an arc pass it as the plan does.
#[inline(never)]
pub(super) fn turned_early(input: &ReplanInput, spent: &(u32, u32)) -> Option<Replanned> {
    if !(input.arc_duty < 1.0) {
        return None;
    }
    let wide = ReplanInput {
        margin: EARLY_TURN_MARGIN * input.margin,
        ..*input
    };
    // Out of the curvature's reach, no share of the turn reaches either.
    let turn = Turn::of(input)?;
    // Every try aims the bevel at the same target: each costs the same checks.
    let (bevels, first) = aimed_bevels(input, turn.local);
    let mut tries = EARLY_CHECKS / (bevels.len() - first);
    let floor = input.scenario.options.min_clearance + wide.margin - SCREEN_SLACK_MM;
    let (arc, line) = whole_turn(&wide, &turn);
    if screened_clearance(&wide, &turn, arc, line) >= floor {
        if let Some(found) = front_loaded(&wide, spent) {
            return Some(found);
        }
        tries -= 1;
    }
    largest_share(&wide, &turn, tries, spent)
}

/// The turn the target asks for, from the tip: worked out once a reading (the angle is a
/// bisection of 24 sines and cosines) for the whole turn and every share of it.
struct Turn {
    /// The target in the tip's axes.
    local: V3,
    /// Its distance to the side of the heading (mm).
    side: f32,
    /// The angle (rad) the full estimated curvature turns until the needle heads at it.
    phi: f32,
}

impl Turn {
    /// `None` when the target is out of the curvature's reach, or nothing is left to turn.
    fn of(input: &ReplanInput) -> Option<Turn> {
        let local = input.tip.r.transpose() * (input.target - input.tip.p);
        let side = crate::fmath::sqrt(local.x * local.x + local.y * local.y);
        let phi = heading_turn(side, local.z, input.radius)?;
        Some(Turn { local, side, phi })
    }
}

/// The whole turn ([`front_loaded`]) as [`part_then_arc`] gives a share: its arc at the full
/// curvature (mm), then the line to the target (an arc at duty 0).
fn whole_turn(input: &ReplanInput, turn: &Turn) -> (f32, ThenArc) {
    let (r, phi) = (input.radius, turn.phi);
    let (dx, dz) = (
        turn.side - r * (1.0 - crate::fmath::cos(phi)),
        turn.local.z - r * crate::fmath::sin(phi),
    );
    let length = crate::fmath::sqrt(dx * dx + dz * dz);
    (r * phi, ThenArc { length, duty: 0.0 })
}

/// The checks the turn made early may spend in one reading, on what the screen keeps of the
/// whole turn, then of the shares: each predicts the motor steps along the rest of the path,
/// and a reading's budget on the device is 1 M instructions (docs/firmware.md; the lab row's
/// largest reading is 0.40 M). Eight reached no more on space-clinical, four less
/// (docs/execution.md, "Part of the turn made early").
const EARLY_CHECKS: usize = 6;

/// The largest share of the turn the obstacles leave (at `wide`'s margin), a tenth less at a
/// time, then the arc through the target, as long as that arc needs no more than the plan's
/// share. Each share is screened on its ideal arcs first (closed form); at most `tries` of those
/// the screen keeps get the check. Share 0 is the one arc through the target.
fn largest_share(
    wide: &ReplanInput,
    turn: &Turn,
    tries: usize,
    spent: &(u32, u32),
) -> Option<Replanned> {
    let floor = wide.scenario.options.min_clearance + wide.margin - SCREEN_SLACK_MM;
    let mut checked = 0;
    if tries == 0 {
        return None;
    }
    for k in (0..TURN_SHARES).rev() {
        let share = k as f32 / TURN_SHARES as f32;
        let Some((arc, then)) = part_then_arc(wide, turn, share) else {
            continue;
        };
        if then.duty > wide.arc_duty + DUTY_SLACK {
            // A smaller share leaves an arc that needs more still.
            break;
        }
        let fits = wide.inserted_mm + arc + then.length <= wide.scenario.needle.length;
        if !(fits && screened_clearance(wide, turn, arc, then) >= floor) {
            continue;
        }
        if let Some(found) = share_of_turn(wide, turn, arc, then, spent) {
            return Some(found);
        }
        checked += 1;
        if checked >= tries {
            break;
        }
    }
    None
}

/// The shares of the turn tried when an obstacle refuses the whole of it: 0.9, 0.8, … of the
/// angle that heads the needle at the target, each followed by the arc through the target.
/// Chosen against easing the whole turn's curvature instead, and against shares a quarter and
/// a fifth apart, on space-clinical (docs/execution.md, "Part of the turn made early").
const TURN_SHARES: u32 = 10;

/// How much nearer an obstacle than the check's floor the screen lets a share's ideal arcs
/// come: the motor steps bend a little differently from ideal arcs (duty cycling, the shaft's
/// twist), and only the check decides.
const SCREEN_SLACK_MM: f32 = 0.1;

/// The least clearance (mm) of part of the turn (`arc` mm at the full curvature) and the arc
/// after it (a line at duty 0) from every obstacle, on the ideal arcs in the plane of the turn:
/// a screen before the check (a few operations an obstacle, no prediction). In a plane scenario
/// the obstacles are cylinders across the plane and the turn is in the plane: the distance
/// across the plane is left out, and half the check's sample spacing taken off, as the check
/// counts them.
fn screened_clearance(input: &ReplanInput, turn: &Turn, arc: f32, then: ThenArc) -> f32 {
    let (local, side) = (turn.local, turn.side);
    if !(side > 0.0) {
        return f32::NAN;
    }
    let (u, z) = (V3::new(local.x / side, local.y / side, 0.0), V3::z());
    let r = input.radius;
    let phi = arc / r;
    let (sin, cos) = crate::fmath::sincos(phi);
    let cylinders = input.scenario.options.workspace == Workspace::PlaneYz;
    let first = Arc {
        centre: u * r,
        start: -u,
        heading: z,
        radius: r,
        sweep: phi,
    };
    let (heading, across) = (z * cos + u * sin, u * cos - z * sin);
    let start = u * (r * (1.0 - cos)) + z * (r * sin);
    let second = |c: V3| {
        if !(then.duty > 0.0) {
            let normal = cylinders.then(|| u.cross(&z));
            return line_distance(start, heading, then.length, c, normal);
        }
        let radius = r / then.duty;
        let arc = Arc {
            centre: start + across * radius,
            start: -across,
            heading,
            radius,
            sweep: then.length / radius,
        };
        arc.distance(c, cylinders)
    };
    let sampled = if cylinders {
        0.5 * super::predict::PLANE_SPACING
    } else {
        0.0
    };
    input
        .scenario
        .obstacles
        .iter()
        .map(|o| {
            let c = input.tip.r.transpose() * (V3::from(o.center) - input.tip.p);
            let nearest = first.distance(c, cylinders).min(second(c));
            nearest - o.radius - sampled
        })
        .fold(f32::INFINITY, f32::min)
}

/// The distance from `c` to the line from `start` along `heading` for `length` mm; with
/// `normal` (the turn plane's unit normal), measured in that plane.
fn line_distance(start: V3, heading: V3, length: f32, c: V3, normal: Option<V3>) -> f32 {
    let d = c - start;
    let along = crate::fmath::clamp(d.dot(&heading), 0.0, length);
    let mut v = d - heading * along;
    if let Some(n) = normal {
        v -= n * v.dot(&n);
    }
    crate::fmath::sqrt(v.dot(&v))
}

/// A circular arc: the points `centre + radius (start cos θ + heading sin θ)`, θ from 0 to
/// `sweep`.
struct Arc {
    centre: V3,
    start: V3,
    heading: V3,
    radius: f32,
    sweep: f32,
}

impl Arc {
    /// The distance from `c` to the arc (`in_plane`: measured in the arc's plane).
    fn distance(&self, c: V3, in_plane: bool) -> f32 {
        let d = c - self.centre;
        let (x, y) = (d.dot(&self.start), d.dot(&self.heading));
        let out_of_plane = if in_plane {
            0.0
        } else {
            (d.dot(&d) - x * x - y * y).max(0.0)
        };
        let theta = crate::fmath::atan2(y, x);
        if (0.0..=self.sweep).contains(&theta) {
            let radial = crate::fmath::sqrt(x * x + y * y) - self.radius;
            return crate::fmath::sqrt(out_of_plane + radial * radial);
        }
        let at = |t: f32| {
            self.centre
                + (self.start * crate::fmath::cos(t) + self.heading * crate::fmath::sin(t))
                    * self.radius
        };
        let normal = self.start.cross(&self.heading);
        let to = |p: V3| {
            let d = c - p;
            let across = if in_plane { d.dot(&normal) } else { 0.0 };
            crate::fmath::sqrt((d.dot(&d) - across * across).max(0.0))
        };
        to(at(0.0)).min(to(at(self.sweep)))
    }
}

/// Part of the turn (`arc` mm at the full curvature), then the arc through the target, if the
/// check passes.
fn share_of_turn(
    input: &ReplanInput,
    turn: &Turn,
    arc: f32,
    then: ThenArc,
    spent: &(u32, u32),
) -> Option<Replanned> {
    let driver = &input.scenario.driver;
    aimed_tries(input, turn.local, spent, |bevel_deg| {
        if !(arc > 0.0) {
            // No turn first: the one arc through the target.
            let (steps, peak) =
                duty_continuation(driver, bevel_deg, then.length, then.duty, input.twist_deg)
                    .ok()?;
            return Some((steps, peak, then.length));
        }
        let (mut steps, peak) =
            duty_continuation(driver, bevel_deg, arc, 1.0, input.twist_deg).ok()?;
        steps.push(duty_step(driver, then.length, then.duty)).ok()?;
        Some((steps, peak, arc + then.length))
    })
}

/// The arc through the target after part of the turn: its length (mm) and its share of the
/// estimated curvature.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ThenArc {
    length: f32,
    duty: f32,
}

/// `share` of the turn that heads the needle at the target, at the full estimated curvature:
/// the arc's length (mm), and the arc through the target from its end (in the same plane, so
/// the bevel stays). A circle tangent to the heading through a point `s` to the side and `a`
/// ahead has curvature 2s / (s² + a²) and turns by 2·atan2(s, a). `None` when the target is
/// out of the curvature's reach, or nothing is left to turn.
fn part_then_arc(input: &ReplanInput, turn: &Turn, share: f32) -> Option<(f32, ThenArc)> {
    let (local, side, r) = (turn.local, turn.side, input.radius);
    let phi = share * turn.phi;
    let (sin, cos) = crate::fmath::sincos(phi);
    // The target from the arc's end, in the plane of the turn: across and along its heading.
    let (dx, dz) = (side - r * (1.0 - cos), local.z - r * sin);
    let (ahead, across) = (dx * sin + dz * cos, dx * cos - dz * sin);
    if !(ahead > 0.0 && across > 0.0) {
        return None;
    }
    let curvature = 2.0 * across / (across * across + ahead * ahead);
    let length = 2.0 * crate::fmath::atan2(across, ahead) / curvature;
    let duty = curvature * r;
    Some((r * phi, ThenArc { length, duty }))
}

#[cfg(test)]
mod tests;
