//! Deterministic starting points for the local solver.
//!
//! A seed is a planar path: a plane through the entry and the target (turned about the
//! entry-target line by `psi`), a heading in that plane (`heading` from the chord), a side for
//! every arc and a split of the chord length among the segments. Seeds cover the headings on a
//! grid and a few splits; each is moved onto the target by [`crate::sqp::restore`] and scored, and
//! the best distinct ones are refined. In plane mode the only plane is the y-z plane and the sides
//! belong to the problem.

use crate::form::SegmentKind;
use crate::kinematics::{entry_basis, insertion_frame, V3};
use crate::problem::{Problem, Vars, MAX_VARS};

/// Headings tried per plane.
pub const HEADINGS: usize = 13;
/// Widest heading from the chord tried (radians, about 80 degrees).
const HEADING_SPAN: f32 = 1.4;

/// Splits of the chord among the segments, per control degree (rows sum to 1).
const SPLITS: [&[[f32; 4]]; 4] = [
    &[[1.0, 0.0, 0.0, 0.0]],
    &[
        [0.5, 0.5, 0.0, 0.0],
        [0.25, 0.75, 0.0, 0.0],
        [0.75, 0.25, 0.0, 0.0],
    ],
    &[
        [0.34, 0.33, 0.33, 0.0],
        [0.2, 0.6, 0.2, 0.0],
        [0.6, 0.2, 0.2, 0.0],
        [0.2, 0.2, 0.6, 0.0],
    ],
    &[
        [0.25, 0.25, 0.25, 0.25],
        [0.1, 0.4, 0.4, 0.1],
        [0.4, 0.1, 0.1, 0.4],
        [0.1, 0.1, 0.4, 0.4],
    ],
];

/// Splits for a form of `len` segments.
pub fn splits(len: usize) -> &'static [[f32; 4]] {
    SPLITS[len.clamp(1, 4) - 1]
}

/// Orthonormal pair spanning the normals of planes through the entry-target line; for a target
/// in the entry frame's b2-b3 plane the first one is b1, so `psi = 0` is the paper's plane.
fn plane_normals(p: &Problem, chord: V3) -> (V3, V3) {
    let basis = entry_basis(p.scenario.entry.direction);
    let b1: V3 = basis.column(0).into();
    let b2: V3 = basis.column(1).into();
    let pick = if libm::fabsf(chord.dot(&b1)) < 0.9 {
        b1
    } else {
        b2
    };
    let a = pick - chord * pick.dot(&chord);
    let a = a / libm::sqrtf(a.dot(&a));
    (a, chord.cross(&a))
}

/// The seed for plane angle `psi`, heading index `h`, arc sides `sides` (bit set: negative side;
/// ignored in plane mode, where the problem fixes the sides) and split `split`. `None` when the
/// heading leaves the tilt cone.
pub fn seed(p: &Problem, psi: f32, h: usize, sides: u8, split: &[f32; 4]) -> Option<Vars> {
    let e = p.scenario.entry.position;
    let t = p.scenario.target.position;
    let d = V3::new(t[0] - e[0], t[1] - e[1], t[2] - e[2]);
    let dist = libm::sqrtf(d.dot(&d));
    let chord = d / dist;
    let (a, b) = plane_normals(p, chord);
    let normal = a * libm::cosf(psi) + b * libm::sinf(psi);
    let angle = -HEADING_SPAN + 2.0 * HEADING_SPAN * h as f32 / (HEADINGS - 1) as f32;
    let heading = chord * libm::cosf(angle) + normal.cross(&chord) * libm::sinf(angle);
    let basis = entry_basis(p.scenario.entry.direction);
    let b1: V3 = basis.column(0).into();
    let b2: V3 = basis.column(1).into();
    let b3: V3 = basis.column(2).into();
    if heading.dot(&b3) < p.cos_max_tilt {
        return None;
    }
    let mut x = [0.0f32; MAX_VARS];
    let theta2 = libm::asinf(heading.dot(&b1).clamp(-1.0, 1.0));
    let theta1 = libm::atan2f(-heading.dot(&b2), heading.dot(&b3));
    x[0] = theta1;
    if !p.plane {
        x[1] = theta2;
    }
    for i in 0..p.form.len() {
        let k = p.length_var(i);
        x[k] = (split[i] * dist * 1.05 / p.radius).clamp(p.lower[k], p.upper[k]);
    }
    if !p.plane {
        // Roll the first arc's bevel so that it bends within the seed plane, then flip per side.
        let f0 = insertion_frame(V3::zeros(), &basis, theta1, theta2);
        let base = libm::atan2f(normal.dot(&f0.e2()), normal.dot(&f0.e1()));
        let mut facing_negative = false;
        let mut arc = 0;
        for i in 0..p.form.len() {
            if p.form.kind(i) != SegmentKind::Arc {
                continue;
            }
            let negative = sides & (1 << arc) != 0;
            let mut roll = if arc == 0 { base } else { 0.0 };
            if negative != facing_negative {
                roll += core::f32::consts::PI;
                facing_negative = negative;
            }
            if let Some(k) = p.bevel_var(i) {
                x[k] = roll;
            }
            arc += 1;
        }
    }
    Some(x)
}
