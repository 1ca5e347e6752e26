//! The target pushed by the needle: soft tissue ahead of the tip deforms and carries the
//! target ahead of it as the tip comes near.

use crate::random::{Draw, SplitMix64};
use planner_core::model::kinematics::{Frame, V3};
use serde::Serialize;

/// How near the tip must come to the target (mm) before the tissue carries the target.
pub const PUSH_RANGE_MM: f32 = 10.0;

/// Least compliance drawn: the stiffest tissue still gives a quarter of the most push.
const LEAST_COMPLIANCE: f64 = 0.25;

/// Largest share of the push across the heading.
const MOST_ACROSS: f64 = 0.3;

/// The push of one run: its size (the most push × a drawn compliance), its direction once the
/// tip comes within [`PUSH_RANGE_MM`], and how far it has gone.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TargetPush {
    /// The push when the tip reaches where the target rested (mm).
    pub push_mm: f32,
    /// Share of the push across the heading.
    pub across: f32,
    /// Direction of the across share in the tip's e1–e2 plane (radians from e1).
    pub across_angle: f32,
    /// Unit direction of the push, fixed when the tip first comes within range.
    pub direction: Option<[f32; 3]>,
    /// How far the tip has come into range (0 to 1, never decreasing: the tissue does not
    /// spring back while the needle is in it).
    pub progress: f32,
}

impl TargetPush {
    /// A push of at most `most_mm` drawn from `g`.
    pub fn draw(g: &mut SplitMix64, most_mm: f32) -> TargetPush {
        let compliance = g.range(LEAST_COMPLIANCE, 1.0);
        let across = g.range(0.0, MOST_ACROSS) as f32;
        let across_angle = g.range(0.0, core::f64::consts::TAU) as f32;
        TargetPush {
            push_mm: (f64::from(most_mm) * compliance) as f32,
            across,
            across_angle,
            direction: None,
            progress: 0.0,
        }
    }

    /// The target's displacement from `rest` with the tip at `tip`.
    pub fn displacement(&mut self, tip: &Frame, rest: V3) -> V3 {
        let near = 1.0 - (tip.p - rest).norm() / PUSH_RANGE_MM;
        if near > 0.0 && self.direction.is_none() {
            let (s, c) = (libm::sinf(self.across_angle), libm::cosf(self.across_angle));
            let d = tip.e3() + (tip.e1() * c + tip.e2() * s) * self.across;
            let d = d / d.norm();
            self.direction = Some([d.x, d.y, d.z]);
        }
        self.progress = self.progress.max(near.clamp(0.0, 1.0));
        match self.direction {
            Some([x, y, z]) => V3::new(x, y, z) * (self.push_mm * self.progress),
            None => V3::zeros(),
        }
    }
}
