//! The tissue's reach: how near the tip could have come to the target in the world a run drew,
//! had its controller known that world (every layer ahead, the tissue's curvature, the true
//! entry and where the target ends), measured as the nearest point of a turn at the full
//! curvature towards the target from the entry, then straight on.
//!
//! Why a ceiling: a needle that turns towards the target as hard as the tissue lets it, from
//! the first millimetre, heads at the target sooner and closer than any path that turns later
//! or less, since the curvature a layer offers at one depth cannot be saved for another. Only a
//! path that turns away first and loops round comes nearer, and no needle is steered so. The
//! obstacles, the needle's length and the tracker are left out, which can only take reach away;
//! so are the chance deviations of each push (a spun line's drift, the spread between arcs: a
//! few percent of the curvature, in a drawn direction), by whose luck a run can end nearer
//! (by at most 1.2 mm over 1000 space-clinical runs). A run whose reach misses by more than the
//! controller's reach tolerance is out of the tissue's reach: no steering gets there but by
//! that luck.

use crate::world::World;
use planner_core::model::kinematics::{Frame, V3};

/// Path length of one step of the turn (mm): the heading turns by under 1e-3 rad a step.
const STEP_MM: f32 = 0.05;

/// Path beyond the straight distance to the target after which the turn is given up (mm).
const LONGEST_BEYOND_MM: f32 = 200.0;

/// The nearest (mm) a tip starting at `start` comes to `target` when it turns towards it at
/// `curvature(s)` (1/mm, at `s` mm along its path) until it heads at it, then goes straight.
///
/// ```
/// use needle_sim::nearest_reach;
/// use planner_core::model::kinematics::{Frame, V3};
///
/// let start = Frame { p: V3::zeros(), r: nalgebra::Matrix3::identity() };
/// // 10 mm to the side and 40 mm ahead: within the reach of a 50 mm radius ...
/// assert!(nearest_reach(&start, V3::new(10.0, 0.0, 40.0), |_| 1.0 / 50.0) < 0.01);
/// // ... but not of a 200 mm radius, whose circle comes no nearer than 200 - |(190, 40)|.
/// let nearest = nearest_reach(&start, V3::new(10.0, 0.0, 40.0), |_| 1.0 / 200.0);
/// assert!((nearest - (200.0 - 190.0f32.hypot(40.0))).abs() < 0.05, "{nearest}");
/// ```
pub fn nearest_reach(start: &Frame, target: V3, curvature: impl Fn(f32) -> f32) -> f32 {
    let (mut p, mut h) = (start.p, start.e3());
    let mut nearest = (target - p).norm();
    let longest = nearest + LONGEST_BEYOND_MM;
    let mut s = 0.0;
    while s < longest {
        let to = target - p;
        let ahead = to.dot(&h);
        if ahead.is_nan() || ahead <= 0.0 {
            break; // abreast of the target: from here on only farther
        }
        let across = to - h * ahead;
        let side = across.norm();
        let turn = curvature(s).max(0.0) * STEP_MM;
        if libm::atan2f(side, ahead) <= turn {
            return 0.0; // heads at it within this step, and a straight line ends on it
        }
        let u = across / side;
        let half = 0.5 * turn;
        p += (h * libm::cosf(half) + u * libm::sinf(half)) * STEP_MM;
        h = h * libm::cosf(turn) + u * libm::sinf(turn);
        s += STEP_MM;
        nearest = nearest.min((target - p).norm());
    }
    nearest
}

impl World {
    /// [`nearest_reach`] in this world: from the true entry to where the target is now, at the
    /// tissue's drawn curvature times the factor of each layer the path is in.
    pub fn nearest_reach(&self) -> f32 {
        let drawn = self.drawn();
        let base = drawn.curvature_factor / self.scenario().needle.curvature_radius;
        let layers = drawn.effects.as_ref().and_then(|e| e.layers.as_ref());
        let factor = |s: f32| layers.map_or(1.0, |l| l.factor_at(s));
        nearest_reach(self.start(), self.true_target(), |s| base * factor(s))
    }
}
