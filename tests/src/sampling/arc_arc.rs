//! The two-arc goal connection, for targets that only an arc can end on (a path that must come
//! round onto the target, or one with no segment left for a line).
//!
//! A single arc from a tip `h` reaches the target only in the plane of the heading and the
//! target's offset `v`, and only if the target lies on its circle: with `perp` the part of `v`
//! normal to the heading, `|v|^2 = 2 rho |perp|`. So for a first arc after a roll `phi`, the
//! length `s` at which `g(s) = 2 rho |perp(s)| - |v(s)|^2` vanishes gives a tip from which one
//! more arc ends on the target. `g` is scanned along the first arc for sign changes (for a fan
//! of first rolls) and each root refined by bisection.

use super::limits::Limits;
use super::SampledSegment;
use crate::reference::frame::Frame;
use core::f64::consts::{PI, TAU};
use planner_core::SegmentKind;

/// First rolls tried in space (evenly spread), besides the roll towards the target.
const ROLLS: usize = 8;
/// Points at which `g` is scanned along the longest first arc.
const SCAN: usize = 32;
/// Bisection steps on a root (the bracket shrinks below 1e-9 of its width).
const BISECTIONS: usize = 32;

/// Candidate two-arc connections from `f` (unchecked for clearance and segment counts), each
/// as the two arcs.
pub fn two_arcs(l: &Limits, f: &Frame) -> Vec<[SampledSegment; 2]> {
    let v = l.target - f.p;
    let perp = v - f.e3 * v.dot(f.e3);
    let mut rolls: Vec<f64> = if l.plane {
        vec![0.0, PI]
    } else {
        (0..ROLLS)
            .map(|k| TAU * k as f64 / ROLLS as f64 - PI)
            .collect()
    };
    if !l.plane && perp.norm() > 0.0 {
        rolls.push(l.roll_towards(f, perp.unit()));
    }
    let mut out = Vec::new();
    for roll in rolls {
        let g = l.roll(f, roll);
        let step = l.max_arc / SCAN as f64;
        let mut previous = gap(l, &g.arc(0.0, l.rho));
        for k in 1..=SCAN {
            let s = step * k as f64;
            let here = gap(l, &g.arc(s, l.rho));
            if previous.signum() != here.signum() {
                let s1 = bisect(l, &g, s - step, s);
                if let Some(second) = last_arc(l, &g.arc(s1, l.rho)) {
                    out.push([
                        SampledSegment {
                            kind: SegmentKind::Arc,
                            roll,
                            length: s1,
                        },
                        second,
                    ]);
                }
            }
            previous = here;
        }
    }
    out
}

/// `2 rho |perp| - |v|^2` at the tip `h`: zero when one arc from `h` ends on the target.
fn gap(l: &Limits, h: &Frame) -> f64 {
    let v = l.target - h.p;
    let perp = v - h.e3 * v.dot(h.e3);
    2.0 * l.rho * perp.norm() - v.dot(v)
}

/// The root of `gap` along the arc from `g` between the lengths `lo` and `hi`.
fn bisect(l: &Limits, g: &Frame, mut lo: f64, mut hi: f64) -> f64 {
    let low_sign = gap(l, &g.arc(lo, l.rho)).signum();
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if gap(l, &g.arc(mid, l.rho)).signum() == low_sign {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The arc from `h` whose circle passes through the target (given `gap` is about zero): rolled
/// towards the target, turned by the target's angle on the circle.
fn last_arc(l: &Limits, h: &Frame) -> Option<SampledSegment> {
    let v = l.target - h.p;
    let along = v.dot(h.e3);
    let perp = v - h.e3 * along;
    if perp.norm() == 0.0 {
        return None;
    }
    let roll = l.roll_towards(h, perp.unit());
    let turn = along.atan2(l.rho - perp.norm()).rem_euclid(TAU);
    Some(SampledSegment {
        kind: SegmentKind::Arc,
        roll,
        length: turn * l.rho,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::frame::V3;
    use needle_sim::random::{seeded, Draw};

    #[test]
    fn two_arcs_end_on_the_target() {
        let mut s = planner_core::Scenario::paper();
        s.options.workspace = planner_core::model::scenario::Workspace::Space;
        let mut l = Limits::new(&s);
        let mut rng = seeded(21);
        let mut found = 0;
        for _ in 0..100 {
            let f = l.insertion(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            l.target = f.p
                + V3::new(
                    rng.range(-60.0, 60.0),
                    rng.range(-60.0, 60.0),
                    rng.range(20.0, 100.0),
                );
            for [a, b] in two_arcs(&l, &f) {
                let h = l.roll(&f, a.roll).arc(a.length, l.rho);
                let end = l.roll(&h, b.roll).arc(b.length, l.rho);
                assert!((end.p - l.target).norm() < 1e-6, "{a:?} {b:?}");
                found += 1;
            }
        }
        assert!(found > 100, "{found} connections");
    }
}
