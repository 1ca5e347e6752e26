//! The steering's last resort: the duty-cycled arc aimed through the target, when no form's
//! continuation reaches it.

use super::replan::{sound, wrapped_deg, ReplanInput, Replanned};
use super::turns::{dead_banded, widened_to_band};
use crate::execute::schedule::duty_continuation;

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
    let aim = wrapped_deg(crate::fmath::atan2(-local.x, local.y));
    let banded = dead_banded(aim, input.dead_band_deg);
    let widened = widened_to_band(aim, input.dead_band_deg);
    let bevels = [banded, widened];
    let tries = if banded == widened {
        &bevels[1..]
    } else {
        &bevels[..]
    };
    tries.iter().find_map(|&bevel_deg| {
        let (steps, peak) = duty_continuation(
            &input.scenario.driver,
            bevel_deg,
            length,
            duty,
            input.twist_deg,
        )
        .ok()?;
        sound(input, steps, peak, length, spent)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::schedule::Op;
    use crate::model::kinematics::{Frame, V3};
    use crate::model::scenario::{Scenario, Workspace};

    /// A tip off its course, 30 mm short of the target and 2 mm to the side of it in a plane
    /// its bevel does not bend in: the duty-cycled arc turns the bevel and reaches it exactly,
    /// at a fraction of the needle's curvature.
    #[test]
    fn the_aimed_duty_cycled_arc_reaches_a_point_to_the_side() {
        let mut scenario = Scenario::paper();
        scenario.options.workspace = Workspace::Space;
        scenario.obstacles.clear();
        let tip = Frame {
            p: V3::new(0.0, 0.0, 50.0),
            r: nalgebra::Matrix3::identity(),
        };
        let target = V3::new(2.0, 0.0, 80.0);
        let r = scenario.needle.curvature_radius;
        let input = ReplanInput {
            scenario: &scenario,
            tip,
            target,
            radius: r,
            twist_deg: 0.0,
            iterations: 10,
            margin: 0.3,
            inserted_mm: 50.0,
            dead_band_deg: 2.0,
            arc_duty: 1.0,
            spend_reserve: true,
        };
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
}
