//! The tracker's and imaging's view of the world: a measurement of the tip (its noise, and
//! with the world's effects its latency, field bias, registration error and missing roll) and
//! of the target (with imaging's rate and delay).

use crate::world::{normal, turned, v3, World};
use planner_core::model::kinematics::V3;
use serde::Serialize;

/// What the tracker reports: the tip and the target as imaging sees them, with noise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// Commanded insertion so far (mm): what the robot knows without the tracker.
    pub depth_mm: f32,
    /// Commanded base rotation so far (degrees, accumulated): the robot's rotation stage.
    pub base_deg: f32,
    /// Measured tip position (mm).
    pub position: [f32; 3],
    /// Measured unit heading.
    pub heading: [f32; 3],
    /// Measured unit bevel direction (arcs curve towards it); reported only when `roll_seen`.
    pub bevel: [f32; 3],
    /// The target as imaging sees it: its displaced position, with the tracker's noise;
    /// reported only when `target_seen`.
    pub target: [f32; 3],
    /// The sensor measures the roll (a 6-DOF coil); a 5-DOF coil does not, and the reading
    /// then carries no bevel.
    pub roll_seen: bool,
    /// A new image of the target arrived for this reading (always, unless imaging runs at its
    /// own rate); without one the reading carries no target.
    pub target_seen: bool,
}

impl World {
    /// A tracker measurement of the tip and the target now (draws the tracker's noise; the
    /// draws are the same whatever the effects, so turning one on moves no other).
    pub fn measure(&mut self) -> Measurement {
        let g = &mut self.tracker;
        let (pos_sd, head_sd) = (self.p.tracker_position_mm, self.p.tracker_heading_deg);
        let noise = [0; 3].map(|_| normal(g, pos_sd));
        let angles = [0; 3].map(|_| normal(g, head_sd).to_radians());
        let target = [0; 3].map(|_| normal(g, pos_sd));
        let seen = self.fx.tip_seen(&self.tip);
        let mut f = seen;
        if angles != [0.0; 3] {
            f = turned(&f, f.e1(), angles[0]);
            f = turned(&f, f.e2(), angles[1]);
            f = f.rolled(angles[2]);
        }
        f.p = seen.p + v3(noise);
        let f = self.fx.distorted(f);
        let imaged = self.fx.target_seen(self.true_target);
        let arr = |v: V3| [v.x, v.y, v.z];
        Measurement {
            depth_mm: self.commanded,
            base_deg: self.torsion.base_deg,
            position: arr(f.p),
            heading: arr(f.e3()),
            bevel: arr(f.e2()),
            target: arr(imaged.unwrap_or(self.true_target) + v3(target)),
            roll_seen: self.fx.roll_seen,
            target_seen: imaged.is_some(),
        }
    }
}
