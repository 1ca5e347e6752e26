//! What the spread of an executed schedule ([`spread`](super::spread)) means for the insertion:
//! the probability that the needle enters an obstacle and the 95th percentile of the miss.
//!
//! Collision: for each obstacle, the probability that the tip crosses its surface where the
//! mean path comes closest in units of the spread along the direction to it (the largest over
//! the path of `Φ(−clearance / σ_n)`: the errors along a path are strongly correlated, so one
//! point stands for its neighbours); over obstacles the probabilities add (Boole's bound, as in
//! chance-constrained planning: Blackmore et al. 2011). The miss: the end point's error with the
//! target's own displacement added, its squared norm matched to a scaled χ² (Patnaik 1949) and
//! the percentile taken by Wilson and Hilferty's cube root.

use super::apriori::{estimator_profile, propagate_steered_with};
use super::obstacle_risk::take;
pub use super::obstacle_risk::{normal_cdf, ObstacleRisk, ObstacleRisks};
use super::perturbation::Perturbation;
use super::risk_kept::{shares, Point, KEEPS, KEPT};
use super::schedule::Schedule;
use super::spread::{propagate, TipSpread};
use crate::estimate::{NoiseModel, STEER_MARGIN_SDS};
use crate::model::kinematics::V3;
use crate::model::scenario::{Scenario, Workspace};
use nalgebra::Matrix3;

/// Where the spread is evaluated along the path (mm between points at most).
pub const RISK_SPACING_MM: f32 = 1.0;

/// Standard deviations beyond which [`normal_cdf`] of minus the clearance is 0 in f32 (it is
/// from 14.9 on).
pub const QUIET_SDS: f32 = 16.0;

/// At least the spread of the position along any unit direction (mm): the square root of the
/// covariance's Frobenius norm, which bounds its largest eigenvalue, with room for rounding
/// (infinite or NaN when the covariance is).
fn sd_bound(covariance: &Matrix3<f32>) -> f32 {
    crate::fmath::sqrt(covariance.norm() * 1.001)
}

/// The standard normal quantile of 0.95.
const Z95: f32 = 1.644_853_6;

/// The execution risk of a schedule under a perturbation model (predicted, first order).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExecutionRisk {
    /// Probability that the needle enters any obstacle (Boole's bound over obstacles, at most 1).
    pub collision_probability: f32,
    /// 95th percentile of the distance from the end of the insertion to the (displaced) target
    /// (mm).
    pub target_error_p95: f32,
    /// The tip at the end of the insertion.
    pub end: TipSpread,
}

/// The predicted execution risk of `schedule` in `scenario` under `p`.
///
/// ```
/// use planner_core::execute::perturbation::Perturbation;
/// use planner_core::execute::risk::execution_risk;
/// use planner_core::execute::schedule::schedule;
/// use planner_core::{plan, Scenario};
///
/// let scenario = Scenario::paper();
/// let best = plan(&scenario).unwrap().best().unwrap().clone();
/// let s = schedule(&scenario, &best).unwrap();
/// let risk = execution_risk(&scenario, &s, &Perturbation::default());
/// assert!(risk.collision_probability > 0.0 && risk.collision_probability < 0.5);
/// assert!(risk.target_error_p95 > 1.0 && risk.target_error_p95 < 10.0);
/// let exact = execution_risk(&scenario, &s, &Perturbation::none());
/// assert!(exact.collision_probability < 1e-6 && exact.target_error_p95 < 0.1);
/// ```
pub fn execution_risk(scenario: &Scenario, schedule: &Schedule, p: &Perturbation) -> ExecutionRisk {
    let mut by_obstacle = [ObstacleRisk::default(); crate::MAX_OBSTACLES];
    execution_risk_by_obstacle(scenario, schedule, p, &mut by_obstacle)
}

/// How the schedule is executed: as it is (open loop), or steered from the tracked tip by the
/// controller whose estimator has the given noise model.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Execution {
    /// The schedule as it is.
    OpenLoop,
    /// Steered: the spread the closed loop leaves
    /// ([`propagate_steered`](super::apriori::propagate_steered)).
    Steered(NoiseModel),
}

/// [`execution_risk`], with each obstacle's share written to `by_obstacle`.
pub fn execution_risk_by_obstacle(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    by_obstacle: &mut ObstacleRisks,
) -> ExecutionRisk {
    risk_by_obstacle(scenario, schedule, p, Execution::OpenLoop, by_obstacle)
}

/// The predicted risk of `schedule` executed as `execution` says, each obstacle's share
/// written to `by_obstacle`.
pub fn risk_by_obstacle(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    execution: Execution,
    by_obstacle: &mut ObstacleRisks,
) -> ExecutionRisk {
    risk_measuring(scenario, schedule, p, execution, by_obstacle, true)
}

/// [`risk_by_obstacle`]; `cull`: a sphere is measured in full only where it may have a chance
/// (within [`QUIET_SDS`] standard deviations of the path), and one with no chance anywhere only
/// where its nearest approach may lie: the same answer bit for bit as measuring every sphere at
/// every point, which `false` does (the reference the culling is tested and timed against).
pub fn risk_measuring(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    execution: Execution,
    by_obstacle: &mut ObstacleRisks,
    cull: bool,
) -> ExecutionRisk {
    let how = if cull { Culling::Kept } else { Culling::None };
    risk_culled(scenario, schedule, p, execution, by_obstacle, how)
}

/// How the spheres far from a point of the walk are left out (each the same answer bit for bit).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Culling {
    /// Every sphere measured at every point.
    None,
    /// Measured as the walk goes (as the device does).
    AsWalked,
    /// The walk kept, then each sphere measured along the runs of points near it (when the
    /// walk fits in [`KEPT`], else as it goes).
    Kept,
}

/// [`risk_measuring`] culling as `how` says.
pub fn risk_culled(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    execution: Execution,
    by_obstacle: &mut ObstacleRisks,
    how: Culling,
) -> ExecutionRisk {
    let cull = how != Culling::None;
    let plane = scenario.options.workspace == Workspace::PlaneYz;
    let initial = ObstacleRisk {
        probability: 0.0,
        clearance: f32::INFINITY,
        sd: 0.0,
        steering_margin: 0.0,
    };
    *by_obstacle = [initial; crate::MAX_OBSTACLES];
    // Steered, a path inside the steering's own margin is one it will not follow: that much of
    // the clearance does not count.
    let profile = match execution {
        Execution::OpenLoop => None,
        Execution::Steered(noise) => Some(estimator_profile(scenario, schedule, p, &noise)),
    };
    let kept = |depth: f32| {
        profile
            .as_ref()
            .map_or(0.0, |e| STEER_MARGIN_SDS * crate::fmath::sqrt(e.at(depth)))
    };
    let walk = |visit: &mut dyn FnMut(&TipSpread)| match &profile {
        None => propagate(scenario, schedule, p, RISK_SPACING_MM, visit),
        Some(estimator) => {
            propagate_steered_with(scenario, schedule, p, estimator, RISK_SPACING_MM, visit)
        }
    };
    // A sphere farther than `quiet` from a point has no chance there that an f32 holds.
    let quiet = |tip: &TipSpread| QUIET_SDS * sd_bound(&tip.covariance);
    let mut done = false;
    let mut end = None;
    if how == Culling::Kept && KEEPS {
        let mut points = heapless::Vec::<Point, KEPT>::new();
        let mut whole = true;
        let e = walk(&mut |tip| {
            let point = Point {
                tip: *tip,
                margin: kept(tip.depth),
                quiet: quiet(tip),
            };
            whole &= points.push(point).is_ok();
        });
        done = whole && shares(scenario, plane, &points, by_obstacle);
        end = Some(e);
    }
    let end = match end {
        Some(e) if done => e,
        _ => {
            // Measured as the walk goes: at each point, a sphere beyond `quiet` is left after its
            // distance unless it has had no chance yet and comes nearer than before.
            walk(&mut |tip| {
                let (margin, q) = (kept(tip.depth), cull.then(|| quiet(tip)));
                for (w, ob) in by_obstacle.iter_mut().zip(&scenario.obstacles) {
                    take(w, tip, margin, ob, plane, q);
                }
            })
        }
    };
    // Steered, the needle follows the displaced target as it is seen: the end strays from
    // the plan by the displacement, but misses the target by the estimate's error alone.
    let shift = match &profile {
        None => p.target_shift_mm * p.target_shift_mm,
        Some(_) => -(p.target_shift_mm * p.target_shift_mm),
    };
    let collision_probability = by_obstacle
        .iter()
        .map(|o| o.probability)
        .sum::<f32>()
        .min(1.0);
    let t = scenario.target.position;
    let miss = end.mean - V3::new(t[0], t[1], t[2]);
    let target_error_p95 = norm_quantile(&miss, &(end.covariance + Matrix3::identity() * shift));
    ExecutionRisk {
        collision_probability,
        target_error_p95,
        end,
    }
}

/// The 95th percentile of `|b + x|` for `x ~ N(0, cov)`: `|b + x|²` matched in mean and
/// variance to `g·χ²(h)`, whose percentile Wilson and Hilferty's approximation gives.
fn norm_quantile(b: &V3, cov: &Matrix3<f32>) -> f32 {
    let mean = cov.trace() + b.norm_squared();
    let variance = 2.0 * (cov * cov).trace() + 4.0 * (b.transpose() * cov * b)[0];
    if !(variance > 0.0) {
        return crate::fmath::sqrt(mean.max(0.0));
    }
    let g = variance / (2.0 * mean);
    let h = 2.0 * mean * mean / variance;
    let k = 2.0 / (9.0 * h);
    let root = 1.0 - k + Z95 * crate::fmath::sqrt(k);
    crate::fmath::sqrt((g * h * root * root * root).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The culling rests on this: beyond [`QUIET_SDS`] standard deviations the chance is 0.
    #[test]
    fn the_chance_is_zero_beyond_the_quiet_distance() {
        let mut x = 14.9f32;
        while x < 1e7 {
            assert_eq!(normal_cdf(-x).to_bits(), 0, "{x}");
            x = f32::from_bits(x.to_bits() + 97);
        }
        for x in [f32::MAX, f32::INFINITY, QUIET_SDS] {
            assert_eq!(normal_cdf(-x).to_bits(), 0, "{x}");
        }
        assert!(normal_cdf(-14.0) > 0.0);
        // The bound holds for a covariance of any orientation.
        let m = Matrix3::new(2.0, 0.5, -0.3, 0.5, 1.0, 0.2, -0.3, 0.2, 0.5);
        let b = sd_bound(&m);
        for n in [
            V3::x(),
            V3::new(1.0, 1.0, -0.5).normalize(),
            V3::new(0.3, -2.0, 1.0).normalize(),
        ] {
            let sd = crate::fmath::sqrt((n.transpose() * m * n)[0]);
            assert!(sd <= b, "{sd} {b}");
        }
    }

    #[test]
    fn the_quantile_of_a_known_distribution() {
        // |x| for isotropic x of sd 1 in 3-D: the χ distribution with 3 degrees of freedom,
        // whose 95th percentile is 2.7955.
        let q = norm_quantile(&V3::zeros(), &Matrix3::identity());
        assert!((q - 2.7955).abs() < 0.01, "{q}");
        // One dimension: |N(0, 1)| has its 95th percentile at 1.96 (the approximation is within
        // a few percent for one degree of freedom).
        let mut one = Matrix3::zeros();
        one[(0, 0)] = 1.0;
        let q = norm_quantile(&V3::zeros(), &one);
        assert!((q - 1.96).abs() < 0.08, "{q}");
        // A bias far larger than the spread: the bias plus 1.645 sd along it.
        let q = norm_quantile(&V3::new(10.0, 0.0, 0.0), &(Matrix3::identity() * 0.01));
        assert!((q - (10.0 + 0.1645)).abs() < 0.02, "{q}");
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-6);
        assert!((normal_cdf(-1.644_853_6) - 0.05).abs() < 1e-5);
    }
}
