//! Needle kinematics (the improved unicycle model on SE(3)) and exact derivatives.
//!
//! The tip carries a frame whose columns are `e1` (normal to the bending plane), `e2` (the bevel
//! direction: an arc curves towards it) and `e3` (the heading). An R segment of length `s` turns
//! the heading towards `e2` by `s / radius`; an L segment moves along `e3`; a bevel rotation turns
//! `e1`, `e2` about `e3`. Every parameter therefore moves the downstream path as a rigid screw,
//! so the derivative of any downstream point `P` is `w × P + v` for the parameter's
//! [`Screw`]: that one rule gives the exact Jacobian of the end point and of every clearance.

use crate::model::form::{Form, SegmentKind, MAX_CONTROL_DEGREE};
use nalgebra::{Matrix3, Vector3};

/// 3-vector of the core's float type.
pub type V3 = Vector3<f32>;

/// Position and orientation of the tip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Tip position.
    pub p: V3,
    /// Columns e1 (bending-plane normal), e2 (bevel direction), e3 (heading).
    pub r: Matrix3<f32>,
}

impl Frame {
    /// Bending-plane normal.
    pub fn e1(&self) -> V3 {
        self.r.column(0).into()
    }
    /// Bevel direction: arcs curve towards it.
    pub fn e2(&self) -> V3 {
        self.r.column(1).into()
    }
    /// Heading.
    pub fn e3(&self) -> V3 {
        self.r.column(2).into()
    }

    /// The frame at `p` with the columns `e1`, `e2`, `e3` (taken as given: unit and
    /// right-handed is the caller's to ensure).
    pub fn from_columns(p: V3, e1: V3, e2: V3, e3: V3) -> Frame {
        Frame {
            p,
            r: Matrix3::from_columns(&[e1, e2, e3]),
        }
    }

    /// The frame turned by `angle` (radians) about the heading: the bevel rotation.
    pub fn rolled(&self, angle: f32) -> Frame {
        let (s, c) = crate::fmath::sincos(angle);
        let (e1, e2) = (self.e1(), self.e2());
        Frame::from_columns(self.p, e1 * c + e2 * s, e2 * c - e1 * s, self.e3())
    }

    /// The frame at the end of a segment of `kind` and length `s` (arcs of radius `radius`).
    pub fn advanced(&self, kind: SegmentKind, s: f32, radius: f32) -> Frame {
        match kind {
            SegmentKind::Line => Frame {
                p: self.p + self.e3() * s,
                r: self.r,
            },
            SegmentKind::Arc => {
                let a = s / radius;
                let (sn, cs) = crate::fmath::sincos(a);
                let (e2, e3) = (self.e2(), self.e3());
                let p = self.p + e2 * (radius * (1.0 - cs)) + e3 * (radius * sn);
                Frame::from_columns(p, self.e1(), e2 * cs - e3 * sn, e3 * cs + e2 * sn)
            }
        }
    }

    /// A point at arc length `t` along a segment starting at this frame.
    pub fn point_at(&self, kind: SegmentKind, t: f32, radius: f32) -> V3 {
        self.advanced(kind, t, radius).p
    }
}

/// An infinitesimal rigid motion: a point `P` moves with velocity `w × P + v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Screw {
    /// Angular part.
    pub w: V3,
    /// Linear part (velocity of the world origin).
    pub v: V3,
}

impl Screw {
    /// Rotation about `axis` through `point` at unit rate, plus a translation `lin`.
    pub fn about(axis: V3, point: V3, lin: V3) -> Screw {
        Screw {
            w: axis,
            v: lin - axis.cross(&point),
        }
    }
    /// Velocity of point `p` under this screw.
    pub fn velocity(&self, p: &V3) -> V3 {
        self.w.cross(p) + self.v
    }
    /// No motion.
    pub const ZERO: Screw = Screw {
        w: V3::new(0.0, 0.0, 0.0),
        v: V3::new(0.0, 0.0, 0.0),
    };
}

/// An orthonormal frame with `e3` along `direction`; in plane mode `e1` is world x.
///
/// The choice is deterministic: `e1` is world x made orthogonal to the direction, or world y when
/// the direction is (nearly) along x.
pub fn entry_basis(direction: [f32; 3]) -> Matrix3<f32> {
    let d = V3::new(direction[0], direction[1], direction[2]);
    let n = crate::fmath::sqrt(d.dot(&d));
    let e3 = d / n;
    let x = V3::new(1.0, 0.0, 0.0);
    let y = V3::new(0.0, 1.0, 0.0);
    let pick = if libm::fabsf(e3.dot(&x)) < 0.9 { x } else { y };
    let e1u = pick - e3 * pick.dot(&e3);
    let e1 = e1u / crate::fmath::sqrt(e1u.dot(&e1u));
    let e2 = e3.cross(&e1);
    Matrix3::from_columns(&[e1, e2, e3])
}

/// Rotation of `v` about unit `axis` by `angle` (Rodrigues).
pub fn rotate(v: V3, axis: V3, angle: f32) -> V3 {
    let (s, c) = crate::fmath::sincos(angle);
    v * c + axis.cross(&v) * s + axis * (axis.dot(&v) * (1.0 - c))
}

/// The first frame of the path: the entry basis turned by `theta2` about its e2, then by
/// `theta1` about its (fixed) e1. The tilt from the nominal axis satisfies
/// cos(tilt) = cos(theta1) cos(theta2).
pub fn insertion_frame(position: V3, basis: &Matrix3<f32>, theta1: f32, theta2: f32) -> Frame {
    let (s1, c1) = crate::fmath::sincos(theta1);
    let (s2, c2) = crate::fmath::sincos(theta2);
    // Rx(theta1) * Ry(theta2) in basis coordinates.
    let turn = Matrix3::new(c2, 0.0, s2, s1 * s2, c1, -s1 * c2, -c1 * s2, s1, c1 * c2);
    Frame {
        p: position,
        r: basis * turn,
    }
}

/// Geometry of one path: the frame at the start of every segment and at the end.
#[derive(Clone, Copy, Debug)]
pub struct PathGeometry {
    /// Segment kinds, entry first.
    pub form: Form,
    /// Frame at the start of segment `i` (after its bevel rotation); `starts[len]` is the end frame.
    pub starts: [Frame; MAX_CONTROL_DEGREE + 1],
    /// Frame at the end of segment `i`, before the next segment's bevel rotation.
    pub ends: [Frame; MAX_CONTROL_DEGREE],
    /// Segment lengths (mm).
    pub lengths: [f32; MAX_CONTROL_DEGREE],
    /// Arc radius (mm).
    pub radius: f32,
}

impl PathGeometry {
    /// Walks the path from `first` (the insertion frame): before segment `i` the bevel is
    /// rolled by `bevels[i]`, then the segment of `lengths[i]` is driven.
    pub fn build(
        form: Form,
        first: Frame,
        lengths: &[f32; MAX_CONTROL_DEGREE],
        bevels: &[f32; MAX_CONTROL_DEGREE],
        radius: f32,
    ) -> PathGeometry {
        let mut starts = [first; MAX_CONTROL_DEGREE + 1];
        let mut ends = [first; MAX_CONTROL_DEGREE];
        let mut f = first;
        for i in 0..form.len() {
            f = f.rolled(bevels[i]);
            starts[i] = f;
            f = f.advanced(form.kind(i), lengths[i], radius);
            ends[i] = f;
        }
        starts[form.len()] = f;
        PathGeometry {
            form,
            starts,
            ends,
            lengths: *lengths,
            radius,
        }
    }

    /// [`PathGeometry::build`] in place, over a path of the same form (a restoration redraws one
    /// path many times; frames past the form's length are never read).
    pub fn rebuild(
        &mut self,
        first: Frame,
        lengths: &[f32; MAX_CONTROL_DEGREE],
        bevels: &[f32; MAX_CONTROL_DEGREE],
    ) {
        self.lengths = *lengths;
        let mut f = first;
        for i in 0..self.form.len() {
            f = f.rolled(bevels[i]);
            self.starts[i] = f;
            f = f.advanced(self.form.kind(i), lengths[i], self.radius);
            self.ends[i] = f;
        }
        self.starts[self.form.len()] = f;
    }

    /// The tip at the end of the path.
    pub fn end(&self) -> V3 {
        self.starts[self.form.len()].p
    }

    /// Total length (mm).
    pub fn total_length(&self) -> f32 {
        self.lengths[..self.form.len()].iter().sum()
    }

    /// Screw of a unit change of segment `i`'s length: the downstream path turns about the
    /// segment's end (arcs) or slides along its end heading (lines).
    pub fn length_screw(&self, i: usize) -> Screw {
        let end = &self.ends[i];
        let e3 = end.e3();
        match self.form.kind(i) {
            SegmentKind::Line => Screw::about(V3::zeros(), end.p, e3),
            // The heading turns towards e2 at rate 1/radius, i.e. about -e1.
            SegmentKind::Arc => Screw::about(-end.e1() / self.radius, end.p, e3),
        }
    }

    /// Screw of a unit bevel rotation before segment `i`: the downstream path turns about the
    /// heading at the segment's start.
    pub fn bevel_screw(&self, i: usize) -> Screw {
        let s = &self.starts[i];
        Screw::about(s.e3(), s.p, V3::zeros())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight_up() -> Frame {
        insertion_frame(V3::zeros(), &entry_basis([0.0, 0.0, 1.0]), 0.0, 0.0)
    }

    #[test]
    fn entry_basis_is_right_handed_with_x_normal_for_z_axis() {
        let b = entry_basis([0.0, 0.0, 2.0]);
        assert_eq!(b.column(0), V3::new(1.0, 0.0, 0.0));
        assert_eq!(b.column(1), V3::new(0.0, 1.0, 0.0));
        assert_eq!(b.column(2), V3::new(0.0, 0.0, 1.0));
        let skew = entry_basis([0.3, -0.5, 0.8]);
        let e1: V3 = skew.column(0).into();
        let e2: V3 = skew.column(1).into();
        let e3: V3 = skew.column(2).into();
        assert!((e1.cross(&e2) - e3).norm() < 1e-6);
    }

    #[test]
    fn quarter_arc_matches_closed_form() {
        let r = 63.7;
        let f = straight_up().advanced(SegmentKind::Arc, r * core::f32::consts::FRAC_PI_2, r);
        // A quarter turn towards +y ends at (0, r, r) heading +y.
        assert!((f.p - V3::new(0.0, r, r)).norm() < 1e-4);
        assert!((f.e3() - V3::new(0.0, 1.0, 0.0)).norm() < 1e-6);
    }

    #[test]
    fn half_turn_bevel_mirrors_the_arc() {
        let r = 50.0;
        let f = straight_up()
            .rolled(core::f32::consts::PI)
            .advanced(SegmentKind::Arc, r * 0.5, r);
        let expect = V3::new(
            0.0,
            -r * (1.0 - crate::fmath::cos(0.5)),
            r * crate::fmath::sin(0.5),
        );
        assert!((f.p - expect).norm() < 1e-4);
    }

    #[test]
    fn insertion_tilt_follows_theta1_then_theta2() {
        let f = insertion_frame(V3::zeros(), &entry_basis([0.0, 0.0, 1.0]), 0.3, 0.2);
        let cos_tilt = f.e3().dot(&V3::new(0.0, 0.0, 1.0));
        assert!((cos_tilt - crate::fmath::cos(0.3) * crate::fmath::cos(0.2)).abs() < 1e-6);
        // theta1 alone keeps the heading in the y-z plane.
        let g = insertion_frame(V3::zeros(), &entry_basis([0.0, 0.0, 1.0]), 0.4, 0.0);
        assert!(g.e3().x.abs() < 1e-7 && g.e2().x.abs() < 1e-7);
    }
}
