//! A scenario's numbers in f64 as the sampler needs them: the tilt cone, the segment bounds, the
//! clearance every point must keep, and the clearance of one arc or line.

use crate::reference::distance::{to_arc, to_line};
use crate::reference::frame::{entry_basis, heading_angles, insertion, Frame, V3};
use needle_sim::random::Draw;
use planner_core::model::scenario::Workspace;
use planner_core::{Scenario, SegmentKind};
use std::sync::Arc;

/// Added to the scenario's smallest clearance, so that a sampled path is not one the planner's
/// f32 check would refuse by rounding (mm).
pub const CLEARANCE_MARGIN: f64 = 0.05;

/// Taken off the tilt bound, the arc and the line limits for the same reason (relative).
const BOUND_MARGIN: f64 = 1e-6;

/// Obstacles the sampler keeps clear of besides the spheres: a label map's distance field (mm
/// from a point to the nearest obstacle), looked at along each segment.
#[derive(Clone)]
pub struct DistanceField {
    /// The distance (mm) at a point.
    pub at: Arc<dyn Fn(V3) -> f64 + Send + Sync>,
    /// Spacing of the points looked at along a segment (mm).
    pub step: f64,
}

impl std::fmt::Debug for DistanceField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DistanceField {{ step: {} }}", self.step)
    }
}

/// The sampler's view of a scenario.
#[derive(Clone, Debug)]
pub struct Limits {
    /// Entry point.
    pub entry: V3,
    /// Entry basis (b1, b2, b3), b3 the nominal axis.
    pub basis: [V3; 3],
    /// Largest tilt of the insertion heading from b3 (radians, margin taken off).
    pub max_tilt: f64,
    /// Target point.
    pub target: V3,
    /// Arc radius (mm).
    pub rho: f64,
    /// Longest arc segment (mm).
    pub max_arc: f64,
    /// Longest line segment (mm).
    pub max_line: f64,
    /// Obstacle spheres (centre, radius).
    pub obstacles: Vec<(V3, f64)>,
    /// Clearance every point of a path keeps from every obstacle surface (mm, margin included).
    pub clearance: f64,
    /// Plane mode: the insertion heading stays in the y-z plane and rolls are 0 or pi.
    pub plane: bool,
    /// Most segments a path may have (the scenario's N).
    pub max_segments: usize,
    /// The longest path the needle can be pushed along: its insertable length (mm).
    pub max_length: f64,
    /// Obstacles given as a distance field, if any (kept `clearance` from too).
    pub field: Option<DistanceField>,
}

impl Limits {
    /// The limits of `s`.
    pub fn new(s: &Scenario) -> Limits {
        let rho = f64::from(s.needle.curvature_radius);
        let shrink = 1.0 - BOUND_MARGIN;
        Limits {
            entry: V3::from_f32(s.entry.position),
            basis: entry_basis(V3::from_f32(s.entry.direction)),
            max_tilt: f64::from(s.entry.max_tilt_deg).to_radians() * shrink,
            target: V3::from_f32(s.target.position),
            rho,
            max_arc: rho * f64::from(s.needle.max_arc_deg).to_radians() * shrink,
            max_line: f64::from(s.max_line_length()) * shrink,
            obstacles: s
                .obstacles
                .iter()
                .map(|o| (V3::from_f32(o.center), f64::from(o.radius)))
                .collect(),
            clearance: f64::from(s.options.min_clearance) + CLEARANCE_MARGIN,
            plane: s.options.workspace == Workspace::PlaneYz,
            max_segments: usize::from(s.options.max_control_degree),
            max_length: f64::from(s.needle.length) * shrink,
            field: None,
        }
    }

    /// Longest segment of `kind` (mm).
    pub fn bound(&self, kind: SegmentKind) -> f64 {
        match kind {
            SegmentKind::Arc => self.max_arc,
            SegmentKind::Line => self.max_line,
        }
    }

    /// Smallest clearance to any obstacle surface along a segment leaving `f` (infinite without
    /// obstacles).
    pub fn clearance_of(&self, f: &Frame, kind: SegmentKind, len: f64) -> f64 {
        let spheres = self
            .obstacles
            .iter()
            .map(|&(c, r)| {
                let d = match kind {
                    SegmentKind::Arc => to_arc(f, len, self.rho, c),
                    SegmentKind::Line => to_line(f, len, c),
                };
                d - r
            })
            .fold(f64::INFINITY, f64::min);
        let Some(field) = &self.field else {
            return spheres;
        };
        let n = (len.abs() / field.step).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| {
                let s = len * i as f64 / n as f64;
                let at = match kind {
                    SegmentKind::Arc => f.arc(s, self.rho),
                    SegmentKind::Line => f.line(s),
                };
                (field.at)(at.p)
            })
            .fold(spheres, f64::min)
    }

    /// The insertion frame for the angles `(theta1, theta2)` (radians), as the reference and the
    /// planner define them.
    pub fn insertion(&self, theta1: f64, theta2: f64) -> Frame {
        insertion(self.entry, &self.basis, theta1, theta2)
    }

    /// Whether the insertion angles lie inside the tilt cone (and in the plane in plane mode).
    pub fn posture_ok(&self, theta1: f64, theta2: f64) -> bool {
        let plane_ok = !self.plane || theta2 == 0.0;
        plane_ok && theta1.cos() * theta2.cos() >= self.max_tilt.cos()
    }

    /// The insertion angles of the heading in the cone nearest to `towards` (a point): the
    /// direction to it, tilted back onto the cone's surface when it lies outside.
    pub fn aimed_posture(&self, towards: V3) -> (f64, f64) {
        let b3 = self.basis[2];
        let d = towards - self.entry;
        let mut perp = d - b3 * d.dot(b3);
        if self.plane {
            perp = perp - self.basis[0] * perp.dot(self.basis[0]);
        }
        if perp.norm() < 1e-12 || self.max_tilt == 0.0 {
            return (0.0, 0.0);
        }
        let tilt = perp.norm().atan2(d.dot(b3)).min(self.max_tilt);
        let h = b3 * tilt.cos() + perp.unit() * tilt.sin();
        self.posture_of(h)
    }

    /// Random insertion angles in the cone (uniform over its solid angle; over the tilt in plane
    /// mode).
    pub fn random_posture(&self, rng: &mut impl Draw) -> (f64, f64) {
        if self.max_tilt == 0.0 {
            return (0.0, 0.0);
        }
        if self.plane {
            return (rng.range(-self.max_tilt, self.max_tilt), 0.0);
        }
        let cos_tilt = rng.range(self.max_tilt.cos(), 1.0);
        let tilt = cos_tilt.clamp(-1.0, 1.0).acos();
        let azimuth = rng.range(0.0, core::f64::consts::TAU);
        let [b1, b2, b3] = self.basis;
        let h = b3 * tilt.cos() + (b1 * azimuth.cos() + b2 * azimuth.sin()) * tilt.sin();
        self.posture_of(h)
    }

    /// The angles of heading `h`, pulled inside the cone if rounding put them just outside.
    fn posture_of(&self, h: V3) -> (f64, f64) {
        let (mut t1, mut t2) = heading_angles(&self.basis, h);
        if self.plane {
            t2 = 0.0;
        }
        let mut k = 0;
        while !self.posture_ok(t1, t2) && k < 60 {
            t1 *= 1.0 - 1e-12;
            t2 *= 1.0 - 1e-12;
            k += 1;
        }
        (t1, t2)
    }

    /// `f` rolled by `phi`; in plane mode a roll of pi flips the frame exactly, so that the path
    /// stays in the plane to the last bit.
    pub fn roll(&self, f: &Frame, phi: f64) -> Frame {
        if phi == 0.0 {
            *f
        } else if self.plane && phi == core::f64::consts::PI {
            Frame {
                e1: -f.e1,
                e2: -f.e2,
                ..*f
            }
        } else {
            f.roll(phi)
        }
    }

    /// The roll that puts the unit vector `u` (normal to the heading) on the bevel's side; 0 or pi
    /// in plane mode.
    pub fn roll_towards(&self, f: &Frame, u: V3) -> f64 {
        if self.plane {
            if u.dot(f.e2) >= 0.0 {
                0.0
            } else {
                core::f64::consts::PI
            }
        } else {
            f.roll_towards(u)
        }
    }

    /// A segment leaving `f`: the frame at its end.
    pub fn advance(&self, f: &Frame, kind: SegmentKind, len: f64) -> Frame {
        match kind {
            SegmentKind::Arc => f.arc(len, self.rho),
            SegmentKind::Line => f.line(len),
        }
    }
}
