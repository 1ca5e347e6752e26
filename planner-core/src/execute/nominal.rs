//! The nominal model executing a schedule: the unicycle model driven by the schedule's commands
//! alone (not by the plan's numbers), so it re-checks what the driver will do: where the tip
//! ends, how close it passes every obstacle, and whether the twist stays within the limit.

use super::schedule::{Op, Schedule, Step};
use crate::model::clearance::closest;
use crate::model::form::SegmentKind;
use crate::model::kinematics::{entry_basis, insertion_frame, Frame, V3};
use crate::model::scenario::Scenario;

/// The tip frame once the posture is set: the insertion frame rolled by the posture's roll.
pub fn posture_frame(scenario: &Scenario, schedule: &Schedule) -> Frame {
    let p = &schedule.posture;
    let basis = entry_basis(scenario.entry.direction);
    let entry = V3::new(p.entry[0], p.entry[1], p.entry[2]);
    insertion_frame(
        entry,
        &basis,
        p.theta1_deg.to_radians(),
        p.theta2_deg.to_radians(),
    )
    .rolled(p.roll_deg.to_radians())
}

/// Executes the schedule on the nominal needle; `segment(start, kind, length)` sees every
/// insertion as the segment it drives. Returns the final tip frame.
pub fn execute(
    scenario: &Scenario,
    schedule: &Schedule,
    segment: impl FnMut(&Frame, SegmentKind, f32, f32),
) -> Frame {
    let radius = scenario.needle.curvature_radius;
    execute_from(
        posture_frame(scenario, schedule),
        &schedule.steps,
        radius,
        segment,
    )
}

/// Executes `steps` on a nominal needle of arc radius `radius` whose tip starts at `tip`, as
/// [`execute`] does; `segment(start, kind, length, radius)` sees each segment with its own
/// radius (a duty-cycled push bends less).
pub fn execute_from(
    mut tip: Frame,
    steps: &[Step],
    radius: f32,
    mut segment: impl FnMut(&Frame, SegmentKind, f32, f32),
) -> Frame {
    for step in steps {
        // Whole turns in alternating directions (spins, duty cycling) leave the bevel where it
        // was.
        let Some((kind, length, r)) = step.op.segment(radius) else {
            if let Op::Rotate { angle_deg } = step.op {
                tip = tip.rolled(angle_deg.to_radians());
            }
            continue;
        };
        segment(&tip, kind, length, r);
        tip = tip.advanced(kind, length, r);
    }
    tip
}

/// Visits the nominal tip path from the entry, points at most `spacing` mm apart.
pub fn sample(scenario: &Scenario, schedule: &Schedule, spacing: f32, mut visit: impl FnMut(V3)) {
    let mut first = true;
    execute(scenario, schedule, |start, kind, length, radius| {
        if first {
            visit(start.p);
            first = false;
        }
        let pieces = libm::ceilf(length / spacing).max(1.0) as u32;
        for k in 1..=pieces {
            visit(start.point_at(kind, length * k as f32 / pieces as f32, radius));
        }
    });
}

/// The largest accumulated twist the steps reach (degrees), counted from the steps themselves: the
/// rotations add up, and a spin's alternating turns start towards zero and reach one turn away.
pub fn peak_twist(schedule: &Schedule) -> f32 {
    let (mut now, mut peak) = (0.0f32, 0.0f32);
    for step in &schedule.steps {
        match step.op {
            Op::Rotate { angle_deg } => now += angle_deg,
            Op::InsertSpin { .. } | Op::InsertDuty { .. } => {
                let turn = if now > 0.0 { -360.0 } else { 360.0 };
                peak = peak.max(libm::fabsf(now + turn));
            }
            Op::Insert { .. } => {}
        }
        peak = peak.max(libm::fabsf(now));
    }
    peak
}

/// What executing a schedule on the nominal needle gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScheduleVerdict {
    /// Distance from the executed end to the target (mm).
    pub target_error: f32,
    /// Smallest clearance to any obstacle surface (mm; infinite without obstacles).
    pub min_clearance: f32,
    /// The accumulated twist stays within the driver's limit.
    pub within_twist: bool,
    /// End within tolerance, clearance above the scenario's minimum, twist within the limit.
    pub feasible: bool,
}

/// Re-checks a schedule against the scenario by executing it (exact clearances per segment).
pub fn check(scenario: &Scenario, schedule: &Schedule) -> ScheduleVerdict {
    let mut min_clearance = f32::INFINITY;
    let end = execute(scenario, schedule, |start, kind, length, radius| {
        for ob in &scenario.obstacles {
            let c = V3::new(ob.center[0], ob.center[1], ob.center[2]);
            let d = closest(start, kind, length, radius, &c).distance - ob.radius;
            min_clearance = min_clearance.min(d);
        }
    });
    let t = &scenario.target.position;
    let miss = end.p - V3::new(t[0], t[1], t[2]);
    let target_error = crate::fmath::sqrt(miss.dot(&miss));
    let within_twist = peak_twist(schedule) <= scenario.driver.max_twist_deg;
    let clear_floor = scenario.options.min_clearance;
    ScheduleVerdict {
        target_error,
        min_clearance,
        within_twist,
        feasible: target_error <= scenario.target.tolerance
            && min_clearance > clear_floor
            && within_twist,
    }
}
