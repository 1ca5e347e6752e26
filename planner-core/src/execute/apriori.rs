//! The spread the closed loop leaves, predicted before the insertion from the plan alone
//! (data-free, as LQG-MP does for a linear controller: van den Berg, Abbeel & Goldberg, IJRR
//! 2011).
//!
//! The steering re-aims every reading at the target from where it estimates the tip: it does
//! not bring the needle back to the plan, it bends what remains of the path so that it still
//! ends on the target. Whatever the perturbations did on the way, the path it leaves is one that
//! ends at the target (moved by the target's own displacement). So the deviation from the plan at
//! a point is the open-loop deviation there ([`execute::spread`](crate::execute::spread): every
//! source as a screw) conditioned on the deviation at the end being the target's displacement:
//! `C(s) − C(s,L) C(L)⁻¹ C(L,s)` plus the target's part, a Gaussian bridge pinned at the target.
//! It is zero at the target, largest midway, and small where the plan bends the needle back
//! soon. On top, the estimator's own uncertainty: the steering's filter run along the nominal
//! path with its noise model, its position covariance at its largest (the filter's covariance
//! does not depend on the measurements, only on where and how often they come).
//!
//! The controller's mean path is the plan: it removes the systematic torsional lag with the
//! rest.

use crate::estimate::{Estimate, NoiseModel};
use crate::execute::nominal::posture_frame;
use crate::execute::perturbation::Perturbation;
use crate::execute::schedule::{Op, Schedule, MAX_STEPS};
use crate::execute::spread::{lever, walk, TipSpread, Twist, WalkPoint};
use crate::matmul::{add_outer, mul, sandwich};
use crate::model::form::SegmentKind;
use crate::model::kinematics::V3;
use crate::model::scenario::Scenario;
use nalgebra::{Matrix3, Matrix6};

/// The full screws of the draws shared along the path, from a first walk.
struct Totals {
    run: Twist,
    segment: [Twist; MAX_STEPS],
    drift: [[Twist; 2]; MAX_STEPS],
    /// Each push's advance screw at its end, times its standard deviation.
    advance: [Twist; MAX_STEPS],
    /// Where the plan ends, and the open-loop covariance there.
    end: V3,
    end_covariance: Matrix3<f32>,
}

fn totals(scenario: &Scenario, schedule: &Schedule, p: &Perturbation, spacing: f32) -> Totals {
    let mut t = Totals {
        run: Twist::zeros(),
        segment: [Twist::zeros(); MAX_STEPS],
        drift: [[Twist::zeros(); 2]; MAX_STEPS],
        advance: [Twist::zeros(); MAX_STEPS],
        end: V3::zeros(),
        end_covariance: Matrix3::zeros(),
    };
    walk(scenario, schedule, p, spacing, &mut |at| {
        t.run = at.src.run_curvature + at.part.curvature;
        if let Some(s) = t.segment.get_mut(at.group) {
            *s = at.src.segment_curvature + at.part.curvature;
        }
        if let Some(d) = t.drift.get_mut(at.group) {
            for k in 0..2 {
                d[k] = at.src.drift[k] + at.part.drift[k];
            }
        }
        if let Some(a) = at.push.and_then(|k| t.advance.get_mut(k)) {
            *a = at.part.advance * at.part.advance_sd;
        }
        let a = lever(&at.mean);
        t.end = at.mean;
        t.end_covariance = sandwich(&a, &at.src.at(at.part, p));
    });
    t
}

/// `Σ σ² s(here) s(end)ᵀ`: how the sources upstream of a point move it and the end together.
fn cross(at: &WalkPoint, t: &Totals, p: &Perturbation) -> Matrix6<f32> {
    let (run, seg, drift) = (
        p.curvature_spread,
        p.segment_curvature_spread,
        p.line_drift_mm_per_mm,
    );
    let mut m = at.src.done;
    add_outer(
        &mut m,
        &(at.src.run_curvature + at.part.curvature),
        &t.run,
        run * run,
    );
    if let (Some(s), Some(d)) = (t.segment.get(at.group), t.drift.get(at.group)) {
        add_outer(
            &mut m,
            &(at.src.segment_curvature + at.part.curvature),
            s,
            seg * seg,
        );
        for k in 0..2 {
            add_outer(
                &mut m,
                &(at.src.drift[k] + at.part.drift[k]),
                &d[k],
                drift * drift,
            );
        }
    }
    if let Some(a) = at.push.and_then(|k| t.advance.get(k)) {
        add_outer(&mut m, &(at.part.advance * at.part.advance_sd), a, 1.0);
    }
    m
}

/// Stretches of the insertion over which the estimator's variance is kept (its largest in each).
pub const ESTIMATOR_STRETCHES: usize = 32;

/// The steering estimator's position variance along the insertion: the largest per axis in each
/// of [`ESTIMATOR_STRETCHES`] equal stretches of depth, and the stretch's length (mm).
pub struct EstimatorProfile {
    variance: [f32; ESTIMATOR_STRETCHES],
    stretch_mm: f32,
    /// The tracker's hidden error (`registration_mm` squared): no fix narrows it, so the tip the
    /// loop steers is off by it wherever the estimate is.
    hidden: f32,
}

impl EstimatorProfile {
    /// The variance per axis at `depth` (mm²), the tracker's hidden error included: how far the
    /// steered tip may be from where the loop believes it, so also the margin the steering keeps
    /// (as [`Estimate::margin_sd`](crate::estimate::Estimate::margin_sd) does).
    pub fn at(&self, depth: f32) -> f32 {
        let i = (depth / self.stretch_mm).max(0.0) as usize;
        self.variance[i.min(ESTIMATOR_STRETCHES - 1)] + self.hidden
    }
}

/// The steering estimator's position variance along the nominal execution of `schedule`, a fix
/// fused every `p.measure_every_mm` (the filter's covariance does not depend on the values
/// fused, only on where and how often they come).
pub fn estimator_profile(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    noise: &NoiseModel,
) -> EstimatorProfile {
    let total: f32 = schedule.steps.iter().map(|s| s.op.inserted_mm()).sum();
    let mut out = EstimatorProfile {
        variance: [0.0; ESTIMATOR_STRETCHES],
        stretch_mm: (total / ESTIMATOR_STRETCHES as f32).max(1e-3),
        hidden: noise.registration_mm * noise.registration_mm,
    };
    let first = noise.entry_position_mm * noise.entry_position_mm;
    out.variance[0] = first;
    estimator_walk(scenario, schedule, p, noise, |depth, c| {
        let v = c[(0, 0)].max(c[(1, 1)]).max(c[(2, 2)]);
        let i = ((depth / out.stretch_mm) as usize).min(ESTIMATOR_STRETCHES - 1);
        out.variance[i] = out.variance[i].max(v);
    });
    out
}

/// Runs the steering's estimator along the nominal execution of `schedule`; `visit` sees the
/// depth and the position covariance after each fix.
fn estimator_walk(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    noise: &NoiseModel,
    mut visit: impl FnMut(f32, &Matrix3<f32>),
) {
    let radius = scenario.needle.curvature_radius;
    let tip = posture_frame(scenario, schedule);
    let t = scenario.target.position;
    let mut est = Estimate::new(tip, V3::new(t[0], t[1], t[2]), noise);
    let spacing = p.measure_every_mm.max(0.05);
    let mut depth = 0.0f32;
    let mut last_arc = false;
    for step in &schedule.steps {
        let Some((kind, length, r)) = step.op.segment(radius) else {
            if let Op::Rotate { angle_deg } = step.op {
                est.rotated(angle_deg, depth);
            }
            last_arc = false;
            continue;
        };
        let spun = !matches!(step.op, Op::Insert { .. });
        if kind == SegmentKind::Arc && !last_arc {
            est.new_arc();
        }
        last_arc = kind == SegmentKind::Arc;
        let pieces = libm::ceilf(length / spacing).max(1.0) as u32;
        for k in 1..=pieces {
            est.advanced(kind, length / pieces as f32, r);
            let at = depth + length * k as f32 / pieces as f32;
            if spun {
                est.spinning(at);
            }
            let f = est.tip;
            let _ = est.fuse_position(f.p);
            let _ = est.fuse_orientation(f.e3(), (!spun).then(|| f.e2()));
            visit(at, &est.position_covariance());
        }
        depth += length;
        if spun {
            est.spun(depth);
        }
    }
}

/// Propagates the closed loop's spread along `schedule` under `p` (the steering's estimator
/// with `noise`), as [`propagate`](crate::execute::spread::propagate) does open loop: `visit`
/// sees the tip at points no more than `spacing` mm apart, its `mean` the planned point.
/// Returns the tip at the end.
///
/// ```
/// use planner_core::execute::perturbation::Perturbation;
/// use planner_core::execute::schedule::schedule;
/// use planner_core::execute::spread::propagate;
/// use planner_core::execute::apriori::propagate_steered;
/// use planner_core::estimate::NoiseModel;
/// use planner_core::{plan, Scenario};
///
/// let scenario = Scenario::paper();
/// let best = plan(&scenario).unwrap().best().unwrap().clone();
/// let s = schedule(&scenario, &best).unwrap();
/// let p = Perturbation::default();
/// let (mut open, mut closed) = (0.0f32, 0.0f32);
/// propagate(&scenario, &s, &p, 1.0, |t| open = open.max(t.covariance.trace()));
/// let end = propagate_steered(&scenario, &s, &p, &NoiseModel::DEFAULT, 1.0, |t| {
///     closed = closed.max(t.covariance.trace())
/// });
/// // Steered, the needle strays far less than open loop, and ends on the target but for the
/// // target's own displacement and the estimate's error.
/// assert!(closed < 0.25 * open, "{closed} {open}");
/// assert!(end.covariance.trace().sqrt() < 1.0);
/// ```
pub fn propagate_steered(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    noise: &NoiseModel,
    spacing: f32,
    visit: impl FnMut(&TipSpread),
) -> TipSpread {
    let estimator = estimator_profile(scenario, schedule, p, noise);
    propagate_steered_with(scenario, schedule, p, &estimator, spacing, visit)
}

/// [`propagate_steered`] with the estimator's profile already run along `schedule`.
pub fn propagate_steered_with(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    estimator: &EstimatorProfile,
    spacing: f32,
    mut visit: impl FnMut(&TipSpread),
) -> TipSpread {
    let t = totals(scenario, schedule, p, spacing);
    let shift = Matrix3::identity() * (p.target_shift_mm * p.target_shift_mm);
    // A floor under the end's covariance keeps the inverse finite where few sources move the
    // end (one source alone moves it along one line).
    let floor = 1e-4 * t.end_covariance.trace() + 1e-9;
    let pinned = (t.end_covariance + Matrix3::identity() * floor)
        .try_inverse()
        .unwrap_or_else(Matrix3::zeros);
    let lever_end = lever(&t.end);
    let mut tip = None;
    walk(scenario, schedule, p, spacing, &mut |at| {
        let a = lever(&at.mean);
        let own = sandwich(&a, &at.src.at(at.part, p));
        let with_end = mul(&mul(&a, &cross(at, &t, p)), &lever_end.transpose());
        let gain = with_end * pinned;
        let bridge = own - gain * with_end.transpose() + gain * shift * gain.transpose();
        let covariance =
            0.5 * (bridge + bridge.transpose()) + Matrix3::identity() * estimator.at(at.depth);
        let spread = TipSpread {
            depth: at.depth,
            planned: at.planned,
            mean: at.planned,
            covariance,
        };
        visit(&spread);
        tip = Some(spread);
    });
    tip.unwrap_or(TipSpread {
        depth: 0.0,
        planned: t.end,
        mean: t.end,
        covariance: Matrix3::identity() * estimator.at(0.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::schedule::schedule;
    use crate::execute::spread::propagate;

    fn paper_schedule() -> (Scenario, Schedule) {
        let scenario = Scenario::paper();
        let report = crate::plan(&scenario).unwrap();
        let best = report.best().unwrap().clone();
        let s = schedule(&scenario, &best).unwrap();
        (scenario, s)
    }

    /// Each perturbation alone: the steered path is pinned at the target (its end strays by
    /// the target's displacement and the estimate's error only), and nowhere strays more than
    /// the open loop at the same point.
    #[test]
    fn the_bridge_is_pinned_at_the_target_and_under_the_open_loop() {
        let (scenario, s) = paper_schedule();
        let noise = NoiseModel::DEFAULT;
        for key in [
            "curvature_spread",
            "segment_curvature_spread",
            "line_drift_mm_per_mm",
            "insertion_error_mm",
            "entry_position_mm",
            "entry_direction_deg",
        ] {
            let mut p = Perturbation::none();
            p.set(key, 2.0 * Perturbation::default().get(key).unwrap())
                .unwrap();
            let estimator = estimator_profile(&scenario, &s, &p, &noise);
            let mut open = [0.0f32; 512];
            let mut n = 0;
            propagate(&scenario, &s, &p, 1.0, |t| {
                if let Some(o) = open.get_mut(n) {
                    *o = t.covariance.trace();
                }
                n += 1;
            });
            let mut k = 0;
            let end = propagate_steered(&scenario, &s, &p, &noise, 1.0, |t| {
                let bridge = t.covariance.trace() - 3.0 * estimator.at(t.depth);
                assert!(bridge <= open[k] * 1.001 + 1e-5, "{key} at {}", t.depth);
                k += 1;
            });
            assert_eq!(k, n, "{key}: the same points");
            let pinned = end.covariance.trace() - 3.0 * estimator.at(end.depth);
            assert!(
                pinned.abs() < 1e-3 * open[n - 1].max(1e-3),
                "{key}: {pinned}"
            );
        }
    }

    /// The tracker's hidden error adds its variance at every depth, so a plan steered by a tracker
    /// with one is predicted riskier (and a bounded plan keeps farther away).
    #[test]
    fn the_hidden_registration_error_widens_the_steered_spread() {
        use crate::execute::risk::{risk_by_obstacle, Execution, ObstacleRisk};
        let (scenario, s) = paper_schedule();
        let p = Perturbation::default();
        let registered = NoiseModel {
            registration_mm: 0.6,
            ..NoiseModel::DEFAULT
        };
        let plain = estimator_profile(&scenario, &s, &p, &NoiseModel::DEFAULT);
        let hidden = estimator_profile(&scenario, &s, &p, &registered);
        for depth in [0.0, 10.0, 45.0, 90.0] {
            let added = hidden.at(depth) - plain.at(depth);
            assert!((added - 0.36).abs() < 1e-5, "{depth}: {added}");
        }
        let mut by = [ObstacleRisk::default(); crate::MAX_OBSTACLES];
        let mut risk = |noise| {
            risk_by_obstacle(&scenario, &s, &p, Execution::Steered(noise), &mut by)
                .collision_probability
        };
        let (without, with) = (risk(NoiseModel::DEFAULT), risk(registered));
        assert!(with > without, "{without} {with}");
    }

    /// Midway the estimator's variance is what its fixes leave, under one reading's (the filter
    /// averages), and larger with a noisier tracker.
    #[test]
    fn the_estimators_part_follows_its_noise_model() {
        let (scenario, s) = paper_schedule();
        let p = Perturbation::default();
        let half: f32 = 0.5 * s.steps.iter().map(|s| s.op.inserted_mm()).sum::<f32>();
        let quiet = estimator_profile(&scenario, &s, &p, &NoiseModel::DEFAULT).at(half);
        let noisy = NoiseModel {
            position_mm: 2.0,
            ..NoiseModel::DEFAULT
        };
        let loud = estimator_profile(&scenario, &s, &p, &noisy).at(half);
        assert!(
            quiet > 0.0 && quiet < 0.25 && loud > 2.0 * quiet,
            "{quiet} {loud}"
        );
    }
}
