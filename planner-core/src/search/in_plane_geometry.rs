//! The needle's geometry within the plane a sweep's seeds lie in ([`super::sweep_plane`]):
//! poses, arcs, exact distances to them, and the closed-form completions of the last two segments
//! onto the target (which lies at `(tx, 0)`, the entry at the origin).

use crate::model::form::SegmentKind;

/// In-plane pose: position in (chord, m) coordinates and heading angle.
#[derive(Clone, Copy, Debug)]
pub struct Pose {
    /// Along the chord (mm).
    pub x: f32,
    /// Across the chord, towards the plane's `m` axis (mm).
    pub y: f32,
    /// Heading (radians from the chord).
    pub psi: f32,
}

/// Unit normal towards which an arc of side `s` (+1 right, -1 left) bends at the heading whose
/// (sin, cos) is given.
fn bend_of((sn, cs): (f32, f32), s: f32) -> (f32, f32) {
    (s * sn, -s * cs)
}

/// The heading at which an arc of side `s` has unit bend normal `n`.
pub fn heading_of_bend(n: (f32, f32), s: f32) -> f32 {
    crate::fmath::atan2(s * n.0, -s * n.1)
}

/// Turning angle in [0, 2 pi) from heading `from` to `to` for side `s` (right turns decrease psi).
pub fn turn(from: f32, to: f32, s: f32) -> f32 {
    crate::fmath::wrap_positive(s * (from - to))
}

/// The pose after a segment of `kind` and length `len` bending to side `s`.
#[cfg(test)]
pub fn advance(p: Pose, kind: SegmentKind, len: f32, s: f32, radius: f32) -> Pose {
    advance_from(p, crate::fmath::sincos(p.psi), kind, len, s, radius).0
}

/// The pose after a segment of `kind` and length `len` bending to side `s`, from the start
/// heading's (sin, cos), already known; also returns the end
/// heading's (sin, cos). The same operations as computing every sine afresh, so the same bits.
// Inlined on the host, where the sweep's callers otherwise stall reading the pose it returns
// through memory; the firmware keeps one copy (flash).
#[cfg_attr(not(target_os = "none"), inline(always))]
pub fn advance_from(
    p: Pose,
    sc: (f32, f32),
    kind: SegmentKind,
    len: f32,
    s: f32,
    radius: f32,
) -> (Pose, (f32, f32)) {
    match kind {
        SegmentKind::Line => (
            Pose {
                x: p.x + len * sc.1,
                y: p.y + len * sc.0,
                psi: p.psi,
            },
            sc,
        ),
        SegmentKind::Arc => {
            let (nx, ny) = bend_of(sc, s);
            let (cx, cy) = (p.x + radius * nx, p.y + radius * ny);
            let psi = p.psi - s * len / radius;
            let end_sc = crate::fmath::sincos(psi);
            let (mx, my) = bend_of(end_sc, s);
            (
                Pose {
                    x: cx - radius * mx,
                    y: cy - radius * my,
                    psi,
                },
                end_sc,
            )
        }
    }
}

/// A segment laid out in the plane, with what distance queries need worked out once (a seed is
/// measured against every obstacle).
#[derive(Clone, Copy, Debug)]
pub struct Drawn {
    kind: SegmentKind,
    start: Pose,
    len: f32,
    side: f32,
    radius: f32,
    /// Line: the heading's unit vector. Arc: the unit normal it bends towards.
    unit: (f32, f32),
    /// Arc: the circle's centre.
    centre: (f32, f32),
    /// Arc: the unit radius from the centre to its end.
    end_radial: (f32, f32),
    /// Where the segment ends.
    pub end: Pose,
    /// (sin, cos) of the end heading.
    pub end_sc: (f32, f32),
}

impl Drawn {
    /// The segment of `kind` and length `len` that starts at `start` and bends to side `s`.
    #[cfg(test)]
    pub fn new(start: Pose, kind: SegmentKind, len: f32, s: f32, radius: f32) -> Drawn {
        Drawn::new_from(start, crate::fmath::sincos(start.psi), kind, len, s, radius)
    }

    /// [`Drawn::new`] from the start heading's (sin, cos), already known (a path's pieces are
    /// drawn one after another: each starts with the heading the previous one ends with).
    pub fn new_from(
        start: Pose,
        sc: (f32, f32),
        kind: SegmentKind,
        len: f32,
        s: f32,
        radius: f32,
    ) -> Drawn {
        let (unit, centre) = match kind {
            SegmentKind::Line => ((sc.1, sc.0), (0.0, 0.0)),
            SegmentKind::Arc => {
                let n = bend_of(sc, s);
                (n, (start.x + radius * n.0, start.y + radius * n.1))
            }
        };
        let (end, end_sc) = advance_from(start, sc, kind, len, s, radius);
        let (bx, by) = bend_of(end_sc, s);
        Drawn {
            end_radial: (-bx, -by),
            kind,
            start,
            len,
            side: s,
            radius,
            unit,
            centre,
            end,
            end_sc,
        }
    }

    /// Squared distance from the point `q` to the segment (exact: the nearest point of the
    /// circle or line, else an end).
    pub fn distance_squared(&self, q: (f32, f32)) -> f32 {
        let sq = |x: f32, y: f32| x * x + y * y;
        let p = &self.start;
        match self.kind {
            SegmentKind::Line => {
                let (dx, dy) = self.unit;
                let t = crate::fmath::clamp((q.0 - p.x) * dx + (q.1 - p.y) * dy, 0.0, self.len);
                sq(q.0 - p.x - t * dx, q.1 - p.y - t * dy)
            }
            SegmentKind::Arc => {
                let (nx, ny) = self.unit;
                let (vx, vy) = (q.0 - self.centre.0, q.1 - self.centre.1);
                // The radius to the start is u = -n; along the arc it turns clockwise for s = +1.
                // `ahead(a, b)`: the sine of the angle from a to b in the turning direction
                // (times their lengths). q's radius lies on the arc when its angle from u, in the
                // turning direction, is at most the arc's (sign tests, no arc tangent).
                let side = self.side;
                let ahead = |a: (f32, f32), b: (f32, f32)| -side * (a.0 * b.1 - a.1 * b.0);
                let v = (vx, vy);
                let e = self.end_radial;
                let from_start = ahead((-nx, -ny), v);
                let on_arc = if self.len >= core::f32::consts::TAU * self.radius {
                    true
                } else if self.len <= core::f32::consts::PI * self.radius {
                    from_start >= 0.0 && ahead(v, e) >= 0.0
                } else {
                    !(from_start < 0.0 && ahead(e, v) > 0.0)
                };
                if on_arc {
                    let off = crate::fmath::sqrt(sq(vx, vy)) - self.radius;
                    off * off
                } else {
                    let end = &self.end;
                    crate::fmath::min(sq(q.0 - p.x, q.1 - p.y), sq(q.0 - end.x, q.1 - end.y))
                }
            }
        }
    }
}

/// How far past half a turn an arc must be (the sine of its turn below minus this) before a
/// completion is dropped unseen: far above the rounding of either way of working out the turn.
const PAST_HALF: f32 = 1e-3;

/// Whether the arc of side `s` from radial `u0` to radial `u1` (not unit: `scale` is the product
/// of their lengths) certainly turns by more than half a circle, and by less than a whole one
/// less the margin: the sine of its turn, from the vectors, is below `-PAST_HALF`.
fn past_half(u0: (f32, f32), u1: (f32, f32), scale: f32, s: f32) -> bool {
    -s * (u0.0 * u1.1 - u0.1 * u1.0) < -PAST_HALF * scale
}

/// The last two pieces of planar paths, completed onto the target in closed form.
#[derive(Clone, Copy, Debug)]
pub struct Tail {
    /// Their kinds.
    pub kinds: (SegmentKind, SegmentKind),
    /// Their sides (+1 right, -1 left).
    pub sides: (f32, f32),
    /// Whether each is an arc that may turn by at most half a circle: completions in which it
    /// certainly turns further are left out before their angles are worked out (an `atan2` or two
    /// each), since they would be refused anyway.
    pub half_turn_at_most: (bool, bool),
}

/// Closed-form completions of `tail` from `p` (its heading's (sin, cos): `sc`) to the target
/// `(tx, 0)`; calls `out(length_a, length_b)` for each.
pub fn complete(
    p: Pose,
    sc: (f32, f32),
    tail: &Tail,
    tx: f32,
    r: f32,
    out: &mut dyn FnMut(f32, f32),
) {
    let (sides, limited) = (tail.sides, tail.half_turn_at_most);
    match tail.kinds {
        (SegmentKind::Arc, SegmentKind::Line) => {
            let s = sides.0;
            let (nx, ny) = bend_of(sc, s);
            let (qx, qy) = (tx - (p.x + r * nx), -(p.y + r * ny));
            let q2 = qx * qx + qy * qy;
            if q2 < r * r {
                return;
            }
            let line = crate::fmath::sqrt(q2 - r * r);
            // The radial at the tangent point, times |q|^2: r q + s line q_perp.
            let tangent = (r * qx - s * line * qy, r * qy + s * line * qx);
            if limited.0 && past_half((-nx, -ny), tangent, q2, s) {
                return;
            }
            let psi_end = crate::fmath::atan2(qy, qx) - s * crate::fmath::atan2(r, line);
            out(r * turn(p.psi, psi_end, s), line);
        }
        (SegmentKind::Line, SegmentKind::Arc) => {
            let s = sides.1;
            let (nx, ny) = bend_of(sc, s);
            let (dx, dy) = (sc.1, sc.0);
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
                if !(limited.1 && past_half((-nx, -ny), (tx - cx, -cy), r, s)) {
                    let psi_end = heading_of_bend(((cx - tx) / r, cy / r), s);
                    out(line, r * turn(p.psi, psi_end, s));
                }
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
            let (nx, ny) = bend_of(sc, s1);
            let (c1x, c1y) = (p.x + r * nx, p.y + r * ny);
            let (ux, uy) = (tx - c1x, -c1y);
            let d = crate::fmath::sqrt(ux * ux + uy * uy);
            if !(d >= r && d <= 3.0 * r) || d == 0.0 {
                return;
            }
            let a = (3.0 * r * r + d * d) / (2.0 * d);
            let h = crate::fmath::sqrt(crate::fmath::max(4.0 * r * r - a * a, 0.0));
            let (ex, ey) = (ux / d, uy / d);
            for sign in [-1.0f32, 1.0] {
                let (c2x, c2y) = (c1x + a * ex - sign * h * ey, c1y + a * ey + sign * h * ex);
                let (joint_x, joint_y) = (c2x - c1x, c2y - c1y);
                let beyond = (limited.0 && past_half((-nx, -ny), (joint_x, joint_y), 2.0 * r, s1))
                    || (limited.1
                        && past_half((-joint_x, -joint_y), (tx - c2x, -c2y), 2.0 * r * r, s2));
                if !beyond {
                    let psi1 =
                        heading_of_bend(((c1x - c2x) / (2.0 * r), (c1y - c2y) / (2.0 * r)), s1);
                    let psi2 = heading_of_bend(((c2x - tx) / r, c2y / r), s2);
                    out(r * turn(p.psi, psi1, s1), r * turn(psi1, psi2, s2));
                }
                if h == 0.0 {
                    break;
                }
            }
        }
        (SegmentKind::Line, SegmentKind::Line) => {}
    }
}

#[cfg(test)]
mod tests;
