//! One obstacle's share of the collision risk, offered point by point along a walk: the chance
//! that the tip crosses its surface there, in units of the spread along the direction to it
//! (see [`super::risk`] for how the shares make the plan's risk).

use super::spread::TipSpread;
use crate::model::kinematics::V3;
use crate::model::scenario::Obstacle;

/// One obstacle's share of the collision risk: where the path comes closest to it in units of
/// the spread.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObstacleRisk {
    /// Probability of crossing its surface (the largest along the path).
    pub probability: f32,
    /// The mean path's clearance to it where that probability is largest (mm).
    pub clearance: f32,
    /// The spread of the tip along the direction to it there (mm).
    pub sd: f32,
    /// Steered: the clearance the steering keeps there by itself
    /// ([`STEER_MARGIN_SDS`](crate::estimate::STEER_MARGIN_SDS) of its estimate), counted out of
    /// `clearance` (mm; 0 open loop).
    pub steering_margin: f32,
}

/// Per-obstacle risks, in the scenario's order.
pub type ObstacleRisks = [ObstacleRisk; crate::MAX_OBSTACLES];

/// The standard normal cumulative distribution.
pub fn normal_cdf(x: f32) -> f32 {
    0.5 * libm::erfcf(-x * core::f32::consts::FRAC_1_SQRT_2)
}

/// Offers `w` the share of `ob` at the point `tip`, where the steering keeps `margin`: taken
/// when its chance is larger, or as large at a smaller clearance. With `quiet`, a point farther
/// than it (where the chance is 0) is left after its distance unless `w` has no chance yet and
/// the point is nearer than `w`'s (the same share as without).
pub(crate) fn take(
    w: &mut ObstacleRisk,
    tip: &TipSpread,
    margin: f32,
    ob: &Obstacle,
    plane: bool,
    quiet: Option<f32>,
) {
    let mut away = tip.mean - V3::new(ob.center[0], ob.center[1], ob.center[2]);
    if plane {
        // A circle of the plane is a cylinder across it.
        away.x = 0.0;
    }
    let distance = away.norm();
    let clearance = distance - ob.radius - margin;
    if let Some(q) = quiet {
        let nearer = w.probability == 0.0 && clearance < w.clearance;
        if clearance > q && clearance > 0.0 && !nearer {
            return;
        }
    }
    let sd = if distance > 0.0 {
        tip.sd_along(&(away / distance))
    } else {
        0.0
    };
    let chance = if sd > 0.0 {
        normal_cdf(-clearance / sd)
    } else if clearance > 0.0 {
        0.0
    } else {
        1.0
    };
    if chance > w.probability || (chance == w.probability && clearance < w.clearance) {
        *w = ObstacleRisk {
            probability: chance,
            clearance,
            sd,
            steering_margin: margin,
        };
    }
}
