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

use super::arc_arc::two_arcs;
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

/// The shortest connection from `f` to the target (arc then line, or line then arc; two arcs
/// when neither passes, see [`two_arcs`]) that stays
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
        (None, None) => two_arcs(l, f)
            .into_iter()
            .filter_map(|arcs| checked(l, f, tail, arcs.to_vec()))
            .min_by(|a, b| a.length.total_cmp(&b.length)),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::frame::V3;
    use needle_sim::random::{seeded, Draw};
    use planner_core::Scenario;

    fn open_limits(plane: bool) -> Limits {
        let mut s = Scenario::paper();
        s.obstacles.clear();
        s.options.max_control_degree = 4;
        if !plane {
            s.options.workspace = planner_core::model::scenario::Workspace::Space;
        }
        Limits::new(&s)
    }

    /// Follows `pieces` from `f` with the frame's own kinematics.
    fn end_of(l: &Limits, f: &Frame, pieces: &[SampledSegment]) -> V3 {
        pieces
            .iter()
            .fold(*f, |g, p| l.roll(&g, p.roll).arc_or_line(p, l.rho))
            .p
    }

    trait Advance {
        fn arc_or_line(&self, p: &SampledSegment, rho: f64) -> Frame;
    }
    impl Advance for Frame {
        fn arc_or_line(&self, p: &SampledSegment, rho: f64) -> Frame {
            match p.kind {
                SegmentKind::Arc => self.arc(p.length, rho),
                SegmentKind::Line => self.line(p.length),
            }
        }
    }

    #[test]
    fn both_forms_end_on_targets_around_random_frames() {
        let mut l = open_limits(false);
        let mut rng = seeded(11);
        let mut found = 0;
        for _ in 0..500 {
            let (t1, t2) = (rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            let f = l.insertion(t1, t2).roll(rng.range(-3.0, 3.0));
            // Ahead of the tip and off its heading by less than the arc radius: outside the
            // circle the arc bends along, so within reach.
            let (a, b) = (rng.range(-40.0, 40.0), rng.range(-40.0, 40.0));
            l.target = f.p + f.e3 * rng.range(70.0, 150.0) + f.e1 * a + f.e2 * b;
            if let Some(c) = connect(&l, &f, Tail::START) {
                found += 1;
                assert!((end_of(&l, &f, &c.pieces) - l.target).norm() < 1e-9);
                let sum: f64 = c.pieces.iter().map(|p| p.length).sum();
                assert!((sum - c.length).abs() < 1e-12);
                assert!(c.length >= (l.target - f.p).norm() - 1e-9);
            }
        }
        assert_eq!(found, 500);
    }

    #[test]
    fn a_line_then_an_arc_ends_on_the_target() {
        let mut l = open_limits(false);
        let mut rng = seeded(13);
        for _ in 0..500 {
            let f = l.insertion(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            let (a, b) = (rng.range(-60.0, 60.0), rng.range(-60.0, 60.0));
            l.target = f.p + f.e3 * rng.range(70.0, 150.0) + f.e1 * a + f.e2 * b;
            let v = l.target - f.p;
            let along = v.dot(f.e3);
            let perp = v - f.e3 * along;
            let (line, arc) = line_then_arc(&l, along, perp.norm()).expect("ahead, within reach");
            let roll = f.roll_towards(perp.unit());
            let pieces = [
                piece(SegmentKind::Line, 0.0, line),
                piece(SegmentKind::Arc, roll, arc),
            ];
            assert!((end_of(&l, &f, &pieces) - l.target).norm() < 1e-9);
        }
    }

    #[test]
    fn plane_connections_stay_in_the_plane() {
        let mut l = open_limits(true);
        let mut rng = seeded(12);
        let mut found = 0;
        for _ in 0..200 {
            let f = l.insertion(rng.range(-0.5, 0.5), 0.0);
            l.target = f.p + f.e3 * rng.range(70.0, 150.0) + f.e2 * rng.range(-40.0, 40.0);
            if let Some(c) = connect(&l, &f, Tail::START) {
                found += 1;
                assert!(c
                    .pieces
                    .iter()
                    .all(|p| p.roll == 0.0 || p.roll == core::f64::consts::PI));
                assert!((end_of(&l, &f, &c.pieces) - l.target).norm() < 1e-9);
            }
        }
        assert_eq!(found, 200);
    }

    #[test]
    fn a_connection_past_n_segments_is_refused() {
        let mut l = open_limits(false);
        let f = l.insertion(0.0, 0.0);
        let three = Tail {
            kind: Some(SegmentKind::Arc),
            run: 10.0,
            count: 3,
        };
        // Off to the side of e1, after N = 4 segments: every connection starts one more.
        l.target = f.p + V3::new(30.0, 0.0, 80.0);
        assert!(connect(&l, &f, Tail { count: 4, ..three }).is_none());
        // After three, only the last arc going on (no roll) and one more arc fit.
        let c = connect(&l, &f, three).expect("the arc goes on, then one more arc");
        let kinds: Vec<SegmentKind> = c.pieces.iter().map(|p| p.kind).collect();
        assert_eq!(kinds, [SegmentKind::Arc, SegmentKind::Arc]);
        assert_eq!(c.pieces[0].roll, 0.0);
        // On the bevel's side already: the arc goes on, and a line ends it.
        l.target = f.p + V3::new(0.0, 30.0, 80.0);
        let c = connect(&l, &f, three).expect("the arc continues");
        assert_eq!(c.pieces[0].roll, 0.0);
        assert_eq!(c.pieces[1].kind, SegmentKind::Line);
    }
}
