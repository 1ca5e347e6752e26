//! The tracker's and imaging's view of the world: a measurement of the tip (its noise, and
//! with the world's effects its latency, field bias, registration error and missing roll) and
//! of the target (with imaging's rate and delay).

use crate::reading::Measurement;
use crate::world::{normal, turned, v3, World};
use planner_core::model::kinematics::V3;

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
