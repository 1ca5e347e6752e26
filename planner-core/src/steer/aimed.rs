//! The steering's last resorts, when no form's continuation reaches the target at the plan's
//! share of the curvature: the turn spent first at the needle's full (estimated) curvature and a
//! spun line to the target, then the duty-cycled arc aimed through it.

use super::continuation::{accepted_miss, sound_within, wrapped_deg, ReplanInput, Replanned};
use super::turns::{dead_banded, widened_to_band};
use crate::execute::schedule::{duty_continuation, duty_step, Steps};

/// The duty-cycled arc from the tip through the target: the bevel turned towards it, then one
/// push at the curvature that passes through it (a circle tangent to the heading through a
/// point `s` to the side and `a` ahead has curvature 2s / (s² + a²) and turns by
/// 2·atan2(s, a)), if the needle bends that much and the check passes. The correction a fixed
/// curvature cannot make: any point ahead within the needle's curvature is reachable.
#[inline(never)]
pub(super) fn aimed_duty(input: &ReplanInput, spent: &(u32, u32)) -> Option<Replanned> {
    let local = input.tip.r.transpose() * (input.target - input.tip.p);
    if !(local.z > 0.0) {
        return None;
    }
    let side = crate::fmath::sqrt(local.x * local.x + local.y * local.y);
    let curvature = 2.0 * side / (side * side + local.z * local.z);
    let duty = curvature * input.radius;
    if !(duty <= 1.0) {
        return None;
    }
    let length = if side > 0.0 {
        2.0 * crate::fmath::atan2(side, local.z) / curvature
    } else {
        local.z
    };
    aimed_tries(input, local, spent, |bevel_deg| {
        duty_continuation(
            &input.scenario.driver,
            bevel_deg,
            length,
            duty,
            input.twist_deg,
        )
        .ok()
        .map(|(steps, peak)| (steps, peak, length))
    })
}

/// The bevel aimed at the target (at `local` in the tip's axes), rounded to the dead band's
/// steps (none, or the band): the continuation `build` makes from each (its steps, peak twist
/// and length), the first that passes the check.
pub(super) fn aimed_tries(
    input: &ReplanInput,
    local: crate::model::kinematics::V3,
    spent: &(u32, u32),
    build: impl Fn(f32) -> Option<(Steps, f32, f32)>,
) -> Option<Replanned> {
    let miss = accepted_miss(input);
    aimed_within(input, local, miss, spent, build)
}

/// [`aimed_tries`] with the predicted miss allowed up to `miss` (mm).
fn aimed_within(
    input: &ReplanInput,
    local: crate::model::kinematics::V3,
    miss: f32,
    spent: &(u32, u32),
    build: impl Fn(f32) -> Option<(Steps, f32, f32)>,
) -> Option<Replanned> {
    let (bevels, first) = aimed_bevels(input, local);
    bevels[first..]
        .iter()
        .find_map(|&bevel_deg| sound_within(input, build(bevel_deg)?, miss, spent))
}

/// The bevels [`aimed_tries`] tries for a target at `local` (in the tip's axes), from the index
/// returned: the aim rounded to the dead band's steps, then widened to the band, or only the
/// latter when they agree. Each is a check.
pub(super) fn aimed_bevels(
    input: &ReplanInput,
    local: crate::model::kinematics::V3,
) -> ([f32; 2], usize) {
    let aim = wrapped_deg(crate::fmath::atan2(-local.x, local.y));
    let banded = dead_banded(aim, input.dead_band_deg);
    let widened = widened_to_band(aim, input.dead_band_deg);
    ([banded, widened], usize::from(banded == widened))
}

/// The turn spent first: the bevel turned towards the target, an arc pushed at the full
/// estimated curvature until the needle heads at the target, then a spun line to it (a
/// duty-cycled push at duty 0), if the check passes.
///
/// Why before [`aimed_duty`]: the constant arc through the target needs the least curvature
/// only if the tissue ahead bends as the estimate says. Layered tissue changes the curvature at
/// every boundary (Majewicz et al. 2012: radii tens of percent apart), and the estimate learns a
/// softer layer only after bending in it; an arc left for the end then asks for more than the
/// needle has (duty 0.99 over the last 30 mm, and the target still missed). A turn made now
/// leaves a line, which needs no curvature, and whatever a later layer changes is corrected from
/// farther away. Only when the reserve is spent (the plan's share no longer reaches): the
/// default world, whose plans keep their share, is steered as before.
#[inline(never)]
pub(super) fn front_loaded(input: &ReplanInput, spent: &(u32, u32)) -> Option<Replanned> {
    front_loaded_at(input, 1.0, spent)
}

/// [`front_loaded`] with the arc pushed at `duty` of the estimated curvature (the line is spun
/// as before).
fn front_loaded_at(input: &ReplanInput, duty: f32, spent: &(u32, u32)) -> Option<Replanned> {
    let local = input.tip.r.transpose() * (input.target - input.tip.p);
    let side = crate::fmath::sqrt(local.x * local.x + local.y * local.y);
    let (ahead, r) = (local.z, input.radius / duty);
    let phi = heading_turn(side, ahead, r)?;
    let arc = r * phi;
    let (across, along) = (
        side - r * (1.0 - crate::fmath::cos(phi)),
        ahead - r * crate::fmath::sin(phi),
    );
    let line = crate::fmath::sqrt(across * across + along * along);
    let driver = &input.scenario.driver;
    aimed_tries(input, local, spent, |bevel_deg| {
        let (mut steps, peak) =
            duty_continuation(driver, bevel_deg, arc, duty, input.twist_deg).ok()?;
        steps.push(duty_step(driver, line, 0.0)).ok()?;
        Some((steps, peak, arc + line))
    })
}

/// The angle (rad) an arc of radius `r`, bent towards a target `side` mm to the side and
/// `ahead` mm ahead, turns until the needle heads at it; `None` when the target is out of
/// reach of that curvature, or there is nothing to turn.
pub(super) fn heading_turn(side: f32, ahead: f32, r: f32) -> Option<f32> {
    if !(ahead > 0.0 && side > 0.0 && 2.0 * side * r <= side * side + ahead * ahead) {
        return None;
    }
    // The line from the arc's end heads at the target where s cos φ − a sin φ + r (1 − cos φ)
    // is zero: s at φ = 0, at most 0 at the turn of the arc through the target, 2·atan2(s, a);
    // bisection, 24 halvings (the angle to 1e-7 rad).
    let gap = |phi: f32| {
        let (sin, cos) = crate::fmath::sincos(phi);
        side * cos - ahead * sin + r * (1.0 - cos)
    };
    let (mut lo, mut hi) = (0.0f32, 2.0 * crate::fmath::atan2(side, ahead));
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if gap(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// The nearest the needle can come to the target when nothing reaches it: the bevel turned
/// towards it and an arc at the full estimated curvature to the point of that circle nearest the
/// target (where the circle's radius through the target meets it, at φ = atan2(a, r − s)), if
/// it passes the check but for the target and comes within `better_than` (mm).
///
/// Why: a continuation that no longer reaches is otherwise kept, its bevel where it was; in a
/// softer layer the needle then bends on in a plane that leaves the target to its side (a run
/// 6.5 mm to the side for its last 45 mm, its estimate within 0.1 mm of the tip). Turning the
/// bevel at the target and bending as hard as the needle can leaves the least miss, and the
/// next reading replans from there, so a layer that bends more than estimated still reaches.
#[inline(never)]
pub(super) fn closest_approach(
    input: &ReplanInput,
    better_than: f32,
    spent: &(u32, u32),
) -> Option<Replanned> {
    let local = input.tip.r.transpose() * (input.target - input.tip.p);
    let side = crate::fmath::sqrt(local.x * local.x + local.y * local.y);
    let (ahead, r) = (local.z, input.radius);
    if !(ahead > 0.0 && side > 0.0 && r > 0.0) {
        return None;
    }
    let arc = r * crate::fmath::atan2(ahead, r - side);
    let driver = &input.scenario.driver;
    aimed_within(input, local, better_than, spent, |bevel_deg| {
        let (steps, peak) = duty_continuation(driver, bevel_deg, arc, 1.0, input.twist_deg).ok()?;
        Some((steps, peak, arc))
    })
}

#[cfg(test)]
pub(in crate::steer) mod tests {
    use super::*;
    use crate::execute::schedule::Op;
    use crate::model::kinematics::{Frame, V3};
    use crate::model::scenario::{Obstacle, Scenario, Workspace};

    /// The paper's needle in 3-D, no obstacle.
    pub(in crate::steer) fn open_space() -> Scenario {
        let mut scenario = Scenario::paper();
        scenario.options.workspace = Workspace::Space;
        scenario.obstacles.clear();
        scenario
    }

    /// A tip at 50 mm heading +z, the target 30 mm ahead and 2 mm to the side, the arcs pushed
    /// at `arc_duty`.
    pub(in crate::steer) fn off_course(scenario: &Scenario, arc_duty: f32) -> ReplanInput<'_> {
        ReplanInput {
            scenario,
            tip: Frame {
                p: V3::new(0.0, 0.0, 50.0),
                r: nalgebra::Matrix3::identity(),
            },
            target: V3::new(2.0, 0.0, 80.0),
            radius: scenario.needle.curvature_radius,
            twist_deg: 0.0,
            iterations: 10,
            margin: 0.3,
            inserted_mm: 50.0,
            dead_band_deg: 2.0,
            arc_duty,
            spend_reserve: true,
            turn_early: false,
        }
    }

    /// A tip off its course, 30 mm short of the target and 2 mm to the side of it in a plane
    /// its bevel does not bend in: the duty-cycled arc turns the bevel and reaches it exactly,
    /// at a fraction of the needle's curvature.
    #[test]
    fn the_aimed_duty_cycled_arc_reaches_a_point_to_the_side() {
        let scenario = open_space();
        let r = scenario.needle.curvature_radius;
        let input = off_course(&scenario, 1.0);
        let found = aimed_duty(&input, &(0, 0)).expect("a duty-cycled continuation");
        assert!(
            found.prediction.target_error < 1e-3,
            "{:?}",
            found.prediction
        );
        let Op::Rotate { angle_deg } = found.steps[0].op else {
            panic!("{:?}", found.steps)
        };
        assert!((angle_deg.abs() - 90.0).abs() < 1e-3, "{angle_deg}");
        let Op::InsertDuty { duty, length_mm } = found.steps[1].op else {
            panic!("{:?}", found.steps)
        };
        let want = 2.0 * 2.0 / (4.0 + 900.0) * r;
        assert!(
            (duty - want).abs() < 1e-4 && length_mm > 30.0,
            "{duty} {length_mm}"
        );
        // Beyond the needle's curvature: none.
        let far_side = ReplanInput {
            target: V3::new(20.0, 0.0, 60.0),
            ..input
        };
        assert!(aimed_duty(&far_side, &(0, 0)).is_none());
    }

    /// The same tip and target: the turn spent first is a short arc at the full curvature and a
    /// spun line, and it ends on the target as exactly as the constant arc does.
    #[test]
    fn the_turn_spent_first_is_a_full_arc_then_a_line_to_the_target() {
        let scenario = open_space();
        let input = off_course(&scenario, 0.8);
        let found = front_loaded(&input, &(0, 0)).expect("a continuation");
        assert!(
            found.prediction.target_error < 1e-3,
            "{:?}",
            found.prediction
        );
        let ops: std::vec::Vec<Op> = found.steps.iter().map(|s| s.op).collect();
        let [Op::Rotate { .. }, Op::InsertDuty {
            length_mm: arc,
            duty: full,
        }, Op::InsertDuty {
            length_mm: line,
            duty: none,
        }] = ops[..]
        else {
            panic!("{ops:?}")
        };
        assert_eq!((full, none), (1.0, 0.0));
        // The constant arc would bend over all 30 mm; this one turns in the first few.
        assert!(arc < 12.0 && line > 18.0, "{arc} {line}");
        // Beyond the needle's curvature: none.
        let far_side = ReplanInput {
            target: V3::new(20.0, 0.0, 60.0),
            ..input
        };
        assert!(front_loaded(&far_side, &(0, 0)).is_none());
    }

    /// A target beyond the needle's curvature (10 mm to the side, 20 mm ahead): the closest
    /// approach turns the bevel at it and bends at full curvature to the circle's point nearest
    /// it, r − |T − C| away; refused when that is no better than asked, or when an obstacle lies
    /// on the way.
    #[test]
    fn the_closest_approach_ends_where_the_full_curvature_comes_nearest() {
        let scenario = open_space();
        let r = scenario.needle.curvature_radius;
        let input = ReplanInput {
            target: V3::new(10.0, 0.0, 70.0),
            ..off_course(&scenario, 0.8)
        };
        assert!(front_loaded(&input, &(0, 0)).is_none());
        assert!(aimed_duty(&input, &(0, 0)).is_none());
        let nearest = r - libm::hypotf(r - 10.0, 20.0);
        let found = closest_approach(&input, 100.0, &(0, 0)).expect("a continuation");
        assert!(
            (found.prediction.target_error - nearest).abs() < 0.01,
            "{nearest} {:?}",
            found.prediction
        );
        let Op::Rotate { angle_deg } = found.steps[0].op else {
            panic!("{:?}", found.steps)
        };
        assert!((angle_deg.abs() - 90.0).abs() < 1e-3, "{angle_deg}");
        assert!(closest_approach(&input, nearest - 0.1, &(0, 0)).is_none());
        let mut blocked = scenario.clone();
        let on_the_way = Obstacle {
            center: [1.0, 0.0, 61.3],
            radius: 1.0,
        };
        blocked.obstacles.push(on_the_way).unwrap();
        let input = ReplanInput {
            scenario: &blocked,
            ..input
        };
        assert!(closest_approach(&input, 100.0, &(0, 0)).is_none());
    }
}
