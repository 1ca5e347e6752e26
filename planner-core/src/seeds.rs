//! Deterministic starting points: a sweep over planar paths that end exactly on the target.
//!
//! A seed lies in a plane through the entry and the target (the y-z plane in plane mode; in 3-D,
//! [`crate::solve::SPACE_PLANES`] planes turned about the entry-target line). In that plane the
//! free parameters of a form (the heading, and the lengths of all but the last two segments) run
//! over a grid, and the last two segments are solved in closed form so that the path ends on
//! the target: arc then line is the tangent from the arc's circle to the target; line then arc is
//! a quadratic in the line's length; arc then opposite arc intersects two circles. Every grid point
//! therefore samples the constraint manifold itself, and the sweep sees every basin wider than
//! its spacing. Seeds are handed on as problem variables.

use crate::form::SegmentKind;
use crate::kinematics::{insertion_frame, V3};
use crate::problem::{Problem, Vars, MAX_VARS};
use crate::MAX_CONTROL_DEGREE;

/// Widest heading from the chord swept (radians, about 86 degrees).
const HEADING_SPAN: f32 = 1.5;

/// Grid sizes: headings, then lengths of each free segment, by control degree.
pub fn grid(len: usize) -> (usize, usize) {
    match len {
        0..=2 => (96, 1),
        3 => (32, 12),
        _ => (14, 6),
    }
}

/// A planar path: heading (radians from the chord, towards `m`), then segments.
#[derive(Clone, Copy, Debug)]
struct Planar {
    heading: f32,
    lengths: [f32; MAX_CONTROL_DEGREE],
}

/// In-plane pose: position in (chord, m) coordinates and heading angle.
#[derive(Clone, Copy, Debug)]
struct Pose {
    x: f32,
    y: f32,
    psi: f32,
}

/// Unit normal towards which an arc of side `s` (+1 right, -1 left) bends at heading `psi`.
fn bend(psi: f32, s: f32) -> (f32, f32) {
    (s * crate::fmath::sin(psi), -s * crate::fmath::cos(psi))
}

/// The heading at which an arc of side `s` has unit bend normal `n`.
fn heading_of_bend(n: (f32, f32), s: f32) -> f32 {
    crate::fmath::atan2(s * n.0, -s * n.1)
}

/// Turning angle in [0, 2 pi) from heading `from` to `to` for side `s` (right turns decrease psi).
fn turn(from: f32, to: f32, s: f32) -> f32 {
    crate::fmath::wrap_positive(s * (from - to))
}

fn advance(p: Pose, kind: SegmentKind, len: f32, s: f32, radius: f32) -> Pose {
    match kind {
        SegmentKind::Line => Pose {
            x: p.x + len * crate::fmath::cos(p.psi),
            y: p.y + len * crate::fmath::sin(p.psi),
            psi: p.psi,
        },
        SegmentKind::Arc => {
            let (nx, ny) = bend(p.psi, s);
            let (cx, cy) = (p.x + radius * nx, p.y + radius * ny);
            let psi = p.psi - s * len / radius;
            let (mx, my) = bend(psi, s);
            Pose {
                x: cx - radius * mx,
                y: cy - radius * my,
                psi,
            }
        }
    }
}

/// Closed-form completions of the last two segments from `p` to the target `(tx, 0)`; calls
/// `out(length_a, length_b)` for each.
fn complete(
    p: Pose,
    kinds: (SegmentKind, SegmentKind),
    sides: (f32, f32),
    tx: f32,
    r: f32,
    out: &mut dyn FnMut(f32, f32),
) {
    match kinds {
        (SegmentKind::Arc, SegmentKind::Line) => {
            let s = sides.0;
            let (nx, ny) = bend(p.psi, s);
            let (qx, qy) = (tx - (p.x + r * nx), -(p.y + r * ny));
            let q2 = qx * qx + qy * qy;
            if q2 < r * r {
                return;
            }
            let line = crate::fmath::sqrt(q2 - r * r);
            let psi_end = crate::fmath::atan2(qy, qx) - s * crate::fmath::atan2(r, line);
            out(r * turn(p.psi, psi_end, s), line);
        }
        (SegmentKind::Line, SegmentKind::Arc) => {
            let s = sides.1;
            let (nx, ny) = bend(p.psi, s);
            let (dx, dy) = (crate::fmath::cos(p.psi), crate::fmath::sin(p.psi));
            let (wx, wy) = (tx - p.x - r * nx, -p.y - r * ny);
            let wd = wx * dx + wy * dy;
            let disc = wd * wd - (wx * wx + wy * wy) + r * r;
            if disc < 0.0 {
                return;
            }
            let root = crate::fmath::sqrt(disc);
            for line in [wd - root, wd + root] {
                if line < 0.0 {
                    continue;
                }
                let (cx, cy) = (p.x + line * dx + r * nx, p.y + line * dy + r * ny);
                let psi_end = heading_of_bend(((cx - tx) / r, cy / r), s);
                out(line, r * turn(p.psi, psi_end, s));
                if root == 0.0 {
                    break;
                }
            }
        }
        (SegmentKind::Arc, SegmentKind::Arc) => {
            let (s1, s2) = sides;
            if s1 == s2 {
                return; // one circle: `pieces` merges such runs into one arc
            }
            let (nx, ny) = bend(p.psi, s1);
            let (c1x, c1y) = (p.x + r * nx, p.y + r * ny);
            let (ux, uy) = (tx - c1x, -c1y);
            let d = crate::fmath::sqrt(ux * ux + uy * uy);
            if !(d >= r && d <= 3.0 * r) || d == 0.0 {
                return;
            }
            let a = (3.0 * r * r + d * d) / (2.0 * d);
            let h = crate::fmath::sqrt((4.0 * r * r - a * a).max(0.0));
            let (ex, ey) = (ux / d, uy / d);
            for sign in [-1.0f32, 1.0] {
                let (c2x, c2y) = (c1x + a * ex - sign * h * ey, c1y + a * ey + sign * h * ex);
                let psi1 = heading_of_bend(((c1x - c2x) / (2.0 * r), (c1y - c2y) / (2.0 * r)), s1);
                let psi2 = heading_of_bend(((c2x - tx) / r, c2y / r), s2);
                out(r * turn(p.psi, psi1, s1), r * turn(psi1, psi2, s2));
                if h == 0.0 {
                    break;
                }
            }
        }
        (SegmentKind::Line, SegmentKind::Line) => {}
    }
}

/// Side (+1 right, -1 left) of each segment for arc-side bits `sides` (bit set: left).
fn segment_sides(p: &Problem, sides: u8) -> [f32; MAX_CONTROL_DEGREE] {
    let mut out = [1.0; MAX_CONTROL_DEGREE];
    let mut arc = 0;
    for (i, o) in out.iter_mut().enumerate().take(p.form.len()) {
        if p.form.kind(i) == SegmentKind::Arc {
            if sides & (1 << arc) != 0 {
                *o = -1.0;
            }
            arc += 1;
        }
    }
    out
}

/// A run of segments swept as one: consecutive arcs bending to the same side lie on one circle,
/// so they are swept as a single arc of up to `count` times the longest arc and written out as
/// `count` equal pieces. Without this, paths whose turn exceeds one arc's bound (the long loops
/// around obstacles that block every short path) would have no seeds at all.
#[derive(Clone, Copy, Debug)]
struct Piece {
    kind: SegmentKind,
    side: f32,
    first: usize,
    count: usize,
}

/// The form of `p` with sides `side`, runs of same-side arcs merged.
fn pieces(
    p: &Problem,
    side: &[f32; MAX_CONTROL_DEGREE],
) -> heapless::Vec<Piece, MAX_CONTROL_DEGREE> {
    let mut out: heapless::Vec<Piece, MAX_CONTROL_DEGREE> = heapless::Vec::new();
    for i in 0..p.form.len() {
        let kind = p.form.kind(i);
        if let Some(last) = out.last_mut() {
            if kind == SegmentKind::Arc && last.kind == SegmentKind::Arc && last.side == side[i] {
                last.count += 1;
                continue;
            }
        }
        // At most one piece per segment.
        let _ = out.push(Piece {
            kind,
            side: side[i],
            first: i,
            count: 1,
        });
    }
    out
}

/// Calls `visit` with the variables of every planar seed of `p` in the plane turned by `psi`, with
/// arc sides `sides` (bit set: the arc bends left of the heading, seen along the plane normal).
///
/// `visit` returns the seed's smallest clearance (negative when it touches an obstacle, minus
/// infinity when it was not evaluated); near misses make the sweep look again, more finely.
pub fn sweep(p: &Problem, psi: f32, sides: u8, visit: &mut dyn FnMut(&Vars) -> f32) {
    let e = p.scenario.entry.position;
    let t = p.scenario.target.position;
    let d = V3::new(t[0] - e[0], t[1] - e[1], t[2] - e[2]);
    let dist = crate::fmath::sqrt(d.dot(&d));
    let chord = d / dist;
    let b1: V3 = p.basis.column(0).into();
    let b2: V3 = p.basis.column(1).into();
    let pick = if libm::fabsf(chord.dot(&b1)) < 0.9 {
        b1
    } else {
        b2
    };
    let a = pick - chord * pick.dot(&chord);
    let a = a / crate::fmath::sqrt(a.dot(&a));
    let normal = a * crate::fmath::cos(psi) + chord.cross(&a) * crate::fmath::sin(psi);
    let m = normal.cross(&chord);
    let plane = SeedPlane {
        chord,
        m,
        normal,
        sides: segment_sides(p, sides),
    };
    let r = p.radius;
    let pieces = pieces(p, &plane.sides);
    let n = pieces.len();
    // Lengths of the pieces, written out per segment.
    let mut emit = |heading: f32, piece_lengths: &[f32; MAX_CONTROL_DEGREE]| -> f32 {
        let mut lengths = [0.0f32; MAX_CONTROL_DEGREE];
        for (piece, len) in pieces.iter().zip(piece_lengths) {
            for l in lengths.iter_mut().skip(piece.first).take(piece.count) {
                *l = len / piece.count as f32;
            }
        }
        match plane.variables(p, &Planar { heading, lengths }) {
            Some(x) => visit(&x),
            None => f32::NEG_INFINITY,
        }
    };
    if n == 1 {
        match pieces[0].kind {
            SegmentKind::Line => {
                emit(0.0, &[dist, 0.0, 0.0, 0.0]);
            }
            SegmentKind::Arc => {
                if dist > 2.0 * r {
                    return;
                }
                let side = pieces[0].side;
                let off = crate::fmath::sqrt(r * r - dist * dist / 4.0);
                for cy in [off, -off] {
                    let cx = dist / 2.0;
                    let h0 = heading_of_bend((cx / r, cy / r), side);
                    let h1 = heading_of_bend(((cx - dist) / r, cy / r), side);
                    emit(h0, &[r * turn(h0, h1, side), 0.0, 0.0, 0.0]);
                }
            }
        }
        return;
    }
    let (headings, steps) = grid(n);
    let free = n - 2;
    let max_free = 1.25 * dist;
    let heading_step = 2.0 * HEADING_SPAN / headings as f32;
    let caps = {
        let mut caps = [0.0f32; MAX_CONTROL_DEGREE];
        for (c, piece) in caps.iter_mut().zip(&pieces).take(free) {
            *c = match piece.kind {
                SegmentKind::Arc => {
                    (p.upper[p.length_var(piece.first)] * r * piece.count as f32).min(max_free)
                }
                SegmentKind::Line => max_free,
            };
        }
        caps
    };
    // One probe: the free pieces at fractions `cell` of their caps, completed onto the target;
    // returns the largest clearance among the completions (how near the probe came to feasible).
    let mut probe = |heading: f32, cell: &[f32; MAX_CONTROL_DEGREE]| -> f32 {
        let mut lengths = [0.0f32; MAX_CONTROL_DEGREE];
        let mut pose = Pose {
            x: 0.0,
            y: 0.0,
            psi: heading,
        };
        for i in 0..free {
            lengths[i] = caps[i] * cell[i];
            pose = advance(pose, pieces[i].kind, lengths[i], pieces[i].side, r);
        }
        let (a, b) = (pieces[n - 2], pieces[n - 1]);
        let mut nearest = f32::NEG_INFINITY;
        complete(
            pose,
            (a.kind, b.kind),
            (a.side, b.side),
            dist,
            r,
            &mut |la, lb| {
                lengths[n - 2] = la;
                lengths[n - 1] = lb;
                nearest = nearest.max(emit(heading, &lengths));
            },
        );
        nearest
    };
    let combos = steps.pow(free as u32);
    for hi in 0..headings {
        let heading = -HEADING_SPAN + heading_step * (hi as f32 + 0.5);
        for combo in 0..combos {
            let mut cell = [0.0f32; MAX_CONTROL_DEGREE];
            let mut c = combo;
            for f in cell.iter_mut().take(free) {
                *f = ((c % steps) as f32 + 0.5) / steps as f32;
                c /= steps;
            }
            let nearest = probe(heading, &cell);
            // A probe that just misses (a thin feasible sliver between obstacles can fall between
            // grid points) is followed by a finer grid over its cell.
            if nearest < 0.0 && nearest > -NEAR_MISS {
                let fine = REFINE.pow(free as u32 + 1);
                for k in 0..fine {
                    let mut kk = k;
                    let off = |kk: &mut usize| {
                        let o = ((*kk % REFINE) as f32 + 0.5) / REFINE as f32 - 0.5;
                        *kk /= REFINE;
                        o
                    };
                    let h = heading + heading_step * off(&mut kk);
                    let mut sub = cell;
                    for f in sub.iter_mut().take(free) {
                        *f += off(&mut kk) / steps as f32;
                    }
                    probe(h, &sub);
                }
            }
        }
    }
}

/// Clearance shortfall (mm) under which a probe's cell is searched again more finely.
const NEAR_MISS: f32 = 4.0;
/// Subdivisions per dimension of a refined cell.
const REFINE: usize = 4;

/// The plane of a sweep and the arcs' sides.
struct SeedPlane {
    chord: V3,
    m: V3,
    normal: V3,
    sides: [f32; MAX_CONTROL_DEGREE],
}

impl SeedPlane {
    /// Problem variables of a planar path; `None` when it leaves the tilt cone or a bound.
    fn variables(&self, p: &Problem, path: &Planar) -> Option<Vars> {
        let heading =
            self.chord * crate::fmath::cos(path.heading) + self.m * crate::fmath::sin(path.heading);
        let basis = &p.basis;
        let b1: V3 = basis.column(0).into();
        let b2: V3 = basis.column(1).into();
        let b3: V3 = basis.column(2).into();
        if heading.dot(&b3) < p.cos_max_tilt {
            return None;
        }
        let mut x = [0.0f32; MAX_VARS];
        let theta2 = crate::fmath::asin(heading.dot(&b1).clamp(-1.0, 1.0));
        let theta1 = crate::fmath::atan2(-heading.dot(&b2), heading.dot(&b3));
        x[0] = theta1;
        if !p.plane {
            x[1] = theta2;
        }
        for i in 0..p.form.len() {
            let k = p.length_var(i);
            let u = path.lengths[i] / p.radius;
            if !(u >= 0.0 && u <= p.upper[k]) {
                return None;
            }
            x[k] = u;
        }
        if !p.plane {
            // Roll the bevel so that e1 is the plane normal (the bevel faces the right of the
            // heading), then flip by pi whenever the next arc bends to the other side.
            let f0 = insertion_frame(V3::zeros(), basis, theta1, theta2);
            let base = crate::fmath::atan2(self.normal.dot(&f0.e2()), self.normal.dot(&f0.e1()));
            let mut facing_left = false;
            let mut first = true;
            for i in 0..p.form.len() {
                if p.form.kind(i) != SegmentKind::Arc {
                    continue;
                }
                let left = self.sides[i] < 0.0;
                let mut roll = if first { base } else { 0.0 };
                if left != facing_left {
                    roll += core::f32::consts::PI;
                    facing_left = left;
                }
                first = false;
                if let Some(k) = p.bevel_var(i) {
                    x[k] = roll;
                }
            }
        }
        Some(x)
    }
}
