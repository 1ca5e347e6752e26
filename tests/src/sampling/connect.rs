//! The exact goal connection: from a tip frame, the pieces that end on the target in closed form.
//!
//! When the target lies dead ahead, a line. Otherwise a roll puts the target in the bending
//! plane on the bevel's side, and either an arc turns the heading until it points at the target
//! and a line reaches it, or a line brings the tip to where an arc ends on the target.
//!
//! Arc then line: in the bending plane, with the circle's centre `m = p + rho e2` and the target at
//! `(qx, qy)` from `m` along `(e2, e3)`, the arc's point after turning by `a` is
//! `rho (-cos a, sin a)` and its heading `(sin a, cos a)`; the line through it reaches the target
//! when `qx cos a - qy sin a = -rho`, i.e. `cos(a + beta) = -rho / r` with `(r, beta)` the polar
//! form of `(qx, qy)`, and its length is then `qx sin a + qy cos a` (which must be >= 0). A
//! target inside the circle (`r < rho`) cannot be reached this way.

use super::limits::Limits;
use super::route::Tail;
use super::SampledSegment;
use crate::reference::frame::Frame;
use core::f64::consts::TAU;
use planner_core::SegmentKind;

/// Largest end error a connection may leave (mm).
pub const END_TOLERANCE: f64 = 1e-6;

/// A target this close to the heading's line counts as dead ahead (mm).
const DEAD_AHEAD: f64 = 1e-9;

/// The pieces that end on the target from `f` (a path whose last segment is `tail`).
#[derive(Clone, Debug)]
pub struct Connection {
    /// One or two pieces (a piece may continue the path's last segment).
    pub pieces: Vec<SampledSegment>,
    /// Their total length (mm).
    pub length: f64,
}

/// The shortest connection from `f` to the target (arc then line, or line then arc) that stays
/// within N segments and the segment bounds, keeps its clearance and ends within
/// [`END_TOLERANCE`] of the target.
pub fn connect(l: &Limits, f: &Frame, tail: Tail) -> Option<Connection> {
    let v = l.target - f.p;
    let along = v.dot(f.e3);
    let perp = v - f.e3 * along;
    if perp.norm() <= DEAD_AHEAD * (1.0 + v.norm()) {
        return (along > 0.0)
            .then(|| vec![piece(SegmentKind::Line, 0.0, along)])
            .and_then(|pieces| checked(l, f, tail, pieces));
    }
    let roll = l.roll_towards(f, perp.unit());
    let g = l.roll(f, roll);
    let arc_first = arc_then_line(l, &g).and_then(|(arc, line)| {
        let mut pieces = vec![piece(SegmentKind::Arc, roll, arc)];
        if line > 0.0 {
            pieces.push(piece(SegmentKind::Line, 0.0, line));
        }
        checked(l, f, tail, pieces)
    });
    let line_first = line_then_arc(l, along, perp.norm()).and_then(|(line, arc)| {
        // The roll commutes with the line, so it is made after it, just before the arc.
        let mut pieces = Vec::new();
        if line > 0.0 {
            pieces.push(piece(SegmentKind::Line, 0.0, line));
        }
        pieces.push(piece(SegmentKind::Arc, roll, arc));
        checked(l, f, tail, pieces)
    });
    match (arc_first, line_first) {
        (Some(a), Some(b)) => Some(if b.length < a.length { b } else { a }),
        (a, b) => a.or(b),
    }
}

/// `pieces` from `f` as a connection, if they keep every limit and end on the target.
fn checked(l: &Limits, f: &Frame, tail: Tail, pieces: Vec<SampledSegment>) -> Option<Connection> {
    let mut t = tail;
    let mut frame = *f;
    for p in &pieces {
        t = t.then(l, p.kind, p.roll, p.length)?;
        let g = l.roll(&frame, p.roll);
        if l.clearance_of(&g, p.kind, p.length) < l.clearance {
            return None;
        }
        frame = l.advance(&g, p.kind, p.length);
    }
    if (frame.p - l.target).norm() >= END_TOLERANCE {
        return None;
    }
    let length = pieces.iter().map(|p| p.length).sum();
    Some(Connection { pieces, length })
}

/// The line length and the arc length that reach a target `along` ahead and `aside` off the
/// heading: after the line the target must lie on the arc's circle, `(aside - rho)^2 + h^2 =
/// rho^2` with `h` the target's distance ahead, so `h = sqrt(2 rho aside - aside^2)`; the arc
/// then turns by `atan2(h, rho - aside)` (at most half a turn).
fn line_then_arc(l: &Limits, along: f64, aside: f64) -> Option<(f64, f64)> {
    let rho = l.rho;
    if aside > 2.0 * rho {
        return None;
    }
    let ahead = (aside * (2.0 * rho - aside)).max(0.0).sqrt();
    let line = along - ahead;
    (line >= 0.0).then(|| (line, ahead.atan2(rho - aside) * rho))
}

fn piece(kind: SegmentKind, roll: f64, length: f64) -> SampledSegment {
    SampledSegment { kind, roll, length }
}

/// The arc length and the line length from `g` (already rolled) to the target, by the tangent
/// condition of the module's comment; the shorter turn when both tangents lead forwards.
fn arc_then_line(l: &Limits, g: &Frame) -> Option<(f64, f64)> {
    let rho = l.rho;
    let q = l.target - (g.p + g.e2 * rho);
    let (qx, qy) = (q.dot(g.e2), q.dot(g.e3));
    let r = qx.hypot(qy);
    if r < rho {
        return None;
    }
    let half = (-rho / r).clamp(-1.0, 1.0).acos();
    let beta = qy.atan2(qx);
    [half - beta, -half - beta]
        .into_iter()
        .map(|a| {
            let a = a.rem_euclid(TAU);
            (a, qx * a.sin() + qy * a.cos())
        })
        .filter(|&(_, line)| line >= -END_TOLERANCE)
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(a, line)| (a * rho, line.max(0.0)))
}
