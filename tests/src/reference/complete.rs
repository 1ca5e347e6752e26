//! Closed-form completions: the last two segments of a path that end exactly on the target.
//!
//! Every completion works in the plane of the arc it bends: local coordinates with `x` along the
//! heading and `y` towards the bevel, the arc's circle centred at `(0, rho)`.

use super::frame::{Frame, V3};
use super::problem::{Cand, Problem, Seg};
use core::f64::consts::{PI, TAU};
use planner_core::SegmentKind::{Arc, Line};

/// Turning angle in `[0, 2 pi)` at which an arc from the origin (heading +x, turning to +y)
/// passes through the local point `(x, y)`, which must lie on its circle.
pub fn arc_angle(x: f64, y: f64, rho: f64) -> f64 {
    let t = x.atan2(rho - y);
    if t < 0.0 {
        t + TAU
    } else {
        t
    }
}

/// The target seen from a frame: along the heading `a`, across it `b >= 0`, unit across `u`.
fn split(f: &Frame, target: V3, eps: f64) -> (f64, f64, V3) {
    let d = target - f.p;
    let a = d.dot(f.e3);
    let w = d - f.e3 * a;
    let b = w.norm();
    if b <= eps {
        (a, 0.0, f.e2)
    } else {
        (a, b, w * (1.0 / b))
    }
}

fn arc(length: f64, roll: f64, pieces: u8) -> Seg {
    Seg {
        kind: Arc,
        length,
        roll,
        pieces,
    }
}

fn line(length: f64) -> Seg {
    Seg {
        kind: Line,
        length,
        roll: 0.0,
        pieces: 1,
    }
}

/// Arc then line to the target from `f` (before the arc's roll): the bending plane must hold the
/// target, turning towards it or away from it; the line leaves the circle on a tangent.
pub fn arc_line(pb: &Problem, f: &Frame, base: &Cand, pieces: u8, out: &mut Vec<Cand>) {
    let rho = pb.rho;
    let (a, b, u) = split(f, pb.target, 1e-12 * pb.scale());
    for side in [1.0, -1.0] {
        // In the plane (e3, side*u) the target is at (a, side*b); circle centre (0, rho).
        let (wx, wy) = (a, side * b - rho);
        let dc = wx.hypot(wy);
        if dc < rho {
            continue;
        }
        let psi = wy.atan2(wx) + (rho / dc).min(1.0).asin();
        let turn = psi.rem_euclid(TAU);
        let mut c = *base;
        c.push(arc(rho * turn, f.roll_towards(u * side), pieces));
        c.push(line((dc * dc - rho * rho).max(0.0).sqrt()));
        out.push(c);
    }
}

/// Line then arc to the target: the arc bends towards the target; the line's length solves
/// `(a - s)^2 + (b - rho)^2 = rho^2` (two roots).
pub fn line_arc(pb: &Problem, f: &Frame, base: &Cand, pieces: u8, out: &mut Vec<Cand>) {
    let rho = pb.rho;
    let (a, b, u) = split(f, pb.target, 1e-12 * pb.scale());
    let roll = f.roll_towards(u);
    if b == 0.0 {
        let mut c = *base;
        c.push(line(a));
        c.push(arc(0.0, roll, pieces));
        out.push(c);
        return;
    }
    let disc = 2.0 * rho * b - b * b;
    if disc < 0.0 {
        return;
    }
    let r = disc.sqrt();
    for s in [a - r, a + r] {
        let mut c = *base;
        c.push(line(s));
        c.push(arc(rho * arc_angle(a - s, b, rho), roll, pieces));
        out.push(c);
    }
}

/// Two arcs to the target, the first in the plane `roll1` sets. When that plane holds the target
/// the second arc is in it too, on the other side: its circle's centre is `2 rho` from the
/// first's and `rho` from the target (circle-circle intersection). Otherwise the second arc
/// leaves the plane, and the first arc's length is a root of `|T - Q|^2 = 2 rho b` (the target on
/// the torus the second arc sweeps), found by scanning and bisection.
#[allow(clippy::too_many_arguments)]
pub fn arc_arc(
    pb: &Problem,
    f: &Frame,
    roll1: f64,
    base: &Cand,
    pieces: (u8, u8),
    out: &mut Vec<Cand>,
) {
    let rho = pb.rho;
    let g = f.roll(roll1);
    let d = pb.target - g.p;
    let (x, y, n) = (d.dot(g.e3), d.dot(g.e2), d.dot(g.e1));
    if n.abs() <= 1e-9 * pb.scale() {
        // In-plane: centres C1 = (0, rho), C2 with |C2 - C1| = 2 rho, |C2 - T| = rho.
        let (dx, dy) = (x, y - rho);
        let dist = dx.hypot(dy);
        if dist < rho || dist > 3.0 * rho || dist == 0.0 {
            return;
        }
        let along = (3.0 * rho * rho + dist * dist) / (2.0 * dist);
        let h = (4.0 * rho * rho - along * along).max(0.0).sqrt();
        let (ux, uy) = (dx / dist, dy / dist);
        for sgn in [1.0, -1.0] {
            let c2 = (along * ux - sgn * h * uy, rho + along * uy + sgn * h * ux);
            let j = (c2.0 / 2.0, (rho + c2.1) / 2.0);
            let t1 = arc_angle(j.0, j.1, rho);
            // The target seen from the junction, heading t1, bevel flipped (turning to -y).
            let (rx, ry) = (x - j.0, y - j.1);
            let (s, c) = t1.sin_cos();
            let (lx, ly) = (rx * c + ry * s, -rx * s + ry * c);
            let t2 = arc_angle(lx, -ly, rho);
            let mut cand = *base;
            cand.push(arc(rho * t1, roll1, pieces.0));
            cand.push(arc(rho * t2, PI, pieces.1));
            out.push(cand);
        }
        return;
    }
    let max = pb.bound(Arc, pieces.0);
    let gap = |s: f64| {
        let q = g.arc(s, rho);
        let (a, b, _) = split(&q, pb.target, 0.0);
        a * a + b * b - 2.0 * rho * b
    };
    let steps = 96;
    let mut s0 = 0.0;
    let mut g0 = gap(s0);
    for k in 1..=steps {
        let s1 = max * f64::from(k) / f64::from(steps);
        let g1 = gap(s1);
        if g0 == 0.0 || g0.signum() != g1.signum() {
            let (mut lo, mut hi, mut glo) = (s0, s1, g0);
            if g0 != 0.0 {
                for _ in 0..80 {
                    let mid = 0.5 * (lo + hi);
                    let gm = gap(mid);
                    if gm.signum() == glo.signum() {
                        lo = mid;
                        glo = gm;
                    } else {
                        hi = mid;
                    }
                }
            }
            let s = if g0 == 0.0 { s0 } else { 0.5 * (lo + hi) };
            let q = g.arc(s, rho);
            let (a, b, u) = split(&q, pb.target, 1e-12 * pb.scale());
            let mut cand = *base;
            cand.push(arc(s, roll1, pieces.0));
            cand.push(arc(rho * arc_angle(a, b, rho), q.roll_towards(u), pieces.1));
            out.push(cand);
        }
        s0 = s1;
        g0 = g1;
    }
}

/// A single arc from the entry through the target, its heading on the cone of half-angle
/// `alpha` (sin alpha = |T - E| / (2 rho)) about the chord, at angle `omega` around it; the
/// minor arc (length `2 alpha rho`) and the major one (`(2 pi - 2 alpha) rho`).
pub fn single_arc(pb: &Problem, omega: f64, pieces: u8, out: &mut Vec<Cand>) {
    let rho = pb.rho;
    let chord = pb.target - pb.entry;
    let dist = chord.norm();
    if dist > 2.0 * rho {
        return;
    }
    let c = chord * (1.0 / dist);
    // u in the plane of b2 and the chord when possible (the y-z plane in plane mode).
    let mut u = pb.basis[0].cross(c);
    if u.norm() < 0.1 {
        u = pb.basis[1].cross(c);
    }
    let u = u.unit();
    let v = c.cross(u);
    let alpha = (dist / (2.0 * rho)).min(1.0).asin();
    let around = u * omega.cos() + v * omega.sin();
    for (cos_a, turn) in [
        (alpha.cos(), 2.0 * alpha),
        (-alpha.cos(), TAU - 2.0 * alpha),
    ] {
        let h = c * cos_a + around * alpha.sin();
        let (t1, t2) = super::frame::heading_angles(&pb.basis, h.unit());
        let t2 = if pb.plane { 0.0 } else { t2 };
        let first = pb.first_frame(t1, t2);
        let bend = (chord - first.e3 * chord.dot(first.e3)).unit();
        let mut cand = Cand::new(t1, t2);
        cand.push(arc(rho * turn, first.roll_towards(bend), pieces));
        out.push(cand);
    }
}

/// The straight line from the entry to the target.
pub fn single_line(pb: &Problem, out: &mut Vec<Cand>) {
    let chord = pb.target - pb.entry;
    let (t1, t2) = super::frame::heading_angles(&pb.basis, chord.unit());
    let t2 = if pb.plane { 0.0 } else { t2 };
    let mut cand = Cand::new(t1, t2);
    cand.push(line(chord.norm()));
    out.push(cand);
}
