//! The in-process controller's roll estimate against the world's true tip roll, at every
//! reading of a closed-loop run: how well the estimator knows the bevel's direction, which a
//! 5-DOF sensor never measures (the filter infers it from how the path bends).

use crate::closed::{closed_loop_observed, ClosedLoopError, ClosedRun, Conditions, Seen};
use crate::run::Planned;
use planner_core::execute::schedule::{Op, Schedule};
use planner_core::model::kinematics::Frame;
use planner_core::steer::{SteerConfig, Steering};
use planner_core::Scenario;
use serde::Serialize;

/// The roll estimate's error at one reading.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RollSample {
    /// Commanded insertion at the reading (mm).
    pub depth_mm: f32,
    /// Signed angle (degrees, in (-180, 180]) about the true heading from the true bevel
    /// direction to the estimated one (projected onto the plane normal to the true heading).
    pub error_deg: f32,
    /// The shaft was spinning (a spun line or a duty-cycled push): the tip's roll changes
    /// faster than the readings, so the error means nothing and summaries leave it out.
    pub spinning: bool,
}

/// The signed roll error (degrees) of `estimate` against `truth`: the angle about the true
/// heading from the true bevel direction to the estimated one projected across the heading;
/// `None` when the estimated bevel lies along the true heading (no roll to compare).
pub fn roll_error_deg(truth: &Frame, estimate: &Frame) -> Option<f32> {
    let heading = truth.e3();
    let bevel = truth.e2();
    let seen = estimate.e2();
    let across = seen - heading * seen.dot(&heading);
    if across.norm() < 1e-6 {
        return None;
    }
    let sin = bevel.cross(&across).dot(&heading);
    let cos = bevel.dot(&across);
    Some(libm::atan2f(sin, cos).to_degrees())
}

/// One closed-loop run steered by the in-process controller (as [`closed_loop_observed`]; the
/// run is the same, bit for bit), with the roll error at every reading it answered.
pub fn roll_trace(
    scenario: &Scenario,
    planned: &Planned,
    schedule: &Schedule,
    conditions: &Conditions<'_>,
    config: &SteerConfig,
    seed: u64,
) -> Result<(ClosedRun, Vec<RollSample>), ClosedLoopError<std::convert::Infallible>> {
    let mut controller =
        Steering::start(scenario, schedule, config).map_err(ClosedLoopError::Start)?;
    let mut samples = Vec::new();
    let observe = |seen: &Seen<'_, Steering>| {
        let estimate = &seen.controller.estimate().tip;
        if let Some(error_deg) = roll_error_deg(seen.tip, estimate) {
            samples.push(RollSample {
                depth_mm: seen.reading.depth_mm,
                error_deg,
                spinning: matches!(seen.step.op, Op::InsertSpin { .. } | Op::InsertDuty { .. }),
            });
        }
    };
    let run = closed_loop_observed(
        scenario,
        planned,
        schedule,
        conditions,
        &mut controller,
        seed,
        observe,
    )?;
    Ok((run, samples))
}

/// The roll errors of some samples, spinning ones left out (degrees).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RollSummary {
    /// Samples counted (not spinning).
    pub samples: usize,
    /// Root mean square of the error.
    pub rms_deg: f32,
    /// Median of the error's size (the upper median of an even count).
    pub median_abs_deg: f32,
    /// Largest size of the error.
    pub max_abs_deg: f32,
}

impl RollSummary {
    /// The summary of the samples that were not spinning (zeros when there are none).
    pub fn of(samples: &[RollSample]) -> RollSummary {
        let mut sizes: Vec<f32> = samples
            .iter()
            .filter(|s| !s.spinning && s.error_deg.is_finite())
            .map(|s| s.error_deg.abs())
            .collect();
        if sizes.is_empty() {
            return RollSummary::default();
        }
        sizes.sort_by(f32::total_cmp);
        let n = sizes.len();
        let square: f64 = sizes.iter().map(|v| f64::from(*v) * f64::from(*v)).sum();
        RollSummary {
            samples: n,
            rms_deg: (square / n as f64).sqrt() as f32,
            median_abs_deg: sizes[n / 2],
            max_abs_deg: sizes[n - 1],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner_core::model::kinematics::{entry_basis, insertion_frame, V3};

    fn frame() -> Frame {
        insertion_frame(V3::zeros(), &entry_basis([0.0, 0.0, 1.0]), 0.2, -0.1)
    }

    #[test]
    fn a_rolled_estimate_is_off_by_its_roll_with_its_sign() {
        let truth = frame();
        for deg in [-170.0f32, -30.0, 0.0, 5.0, 90.0] {
            let e = roll_error_deg(&truth, &truth.rolled(deg.to_radians())).unwrap();
            assert!((e - deg).abs() < 1e-3, "{deg}: {e}");
        }
    }

    #[test]
    fn a_heading_tilted_in_the_bend_plane_is_no_roll_error() {
        let truth = frame();
        let tilted = crate::world::turned(&truth, truth.e1(), 0.3);
        let e = roll_error_deg(&truth, &tilted).unwrap();
        assert!(e.abs() < 1e-3, "{e}");
    }

    #[test]
    fn the_summary_leaves_spinning_samples_out() {
        let at = |error_deg, spinning| RollSample {
            depth_mm: 0.0,
            error_deg,
            spinning,
        };
        let s = RollSummary::of(&[at(3.0, false), at(-4.0, false), at(90.0, true)]);
        assert_eq!(s.samples, 2);
        assert!((s.rms_deg - 12.5f32.sqrt()).abs() < 1e-5);
        assert_eq!(s.max_abs_deg, 4.0);
        assert_eq!(RollSummary::of(&[]).samples, 0);
    }
}
