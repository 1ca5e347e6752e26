//! A whole path as the sampler holds it (insertion angles and segments), put in the planner's
//! segment form and measured against the limits.

use super::limits::Limits;
use super::SampledSegment;
use crate::reference::frame::Frame;
use core::f64::consts::PI;
use planner_core::SegmentKind;

/// The last segment of a path, as far as the next piece may continue it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tail {
    /// Kind of the last segment (`None` before the first).
    pub kind: Option<SegmentKind>,
    /// Length of the last segment so far (mm).
    pub run: f64,
    /// Segments so far.
    pub count: usize,
}

impl Tail {
    /// Before the first segment.
    pub const START: Tail = Tail {
        kind: None,
        run: 0.0,
        count: 0,
    };

    /// Whether a piece of `kind` after a roll of `roll` belongs to the last segment rather than
    /// starting one: a line after a line (rolling while spinning changes nothing of its shape) or
    /// an arc after an arc without a roll.
    pub fn continued_by(&self, kind: SegmentKind, roll: f64) -> bool {
        match (self.kind, kind) {
            (Some(SegmentKind::Line), SegmentKind::Line) => true,
            (Some(SegmentKind::Arc), SegmentKind::Arc) => roll == 0.0,
            _ => false,
        }
    }

    /// The tail after a piece of `kind` and length `len`, or `None` when the piece would make a
    /// segment longer than its bound or the path longer than N segments.
    pub fn then(&self, l: &Limits, kind: SegmentKind, roll: f64, len: f64) -> Option<Tail> {
        let continued = self.continued_by(kind, roll);
        let run = if continued { self.run + len } else { len };
        let count = self.count + usize::from(!continued);
        (run <= l.bound(kind) && count <= l.max_segments).then_some(Tail {
            kind: Some(kind),
            run,
            count,
        })
    }
}

/// The planner's segments of a list of pieces: empty pieces are dropped (their roll carried into
/// the next piece), a line after a line and an arc after an arc without a roll merge into one.
pub fn normalize(pieces: &[SampledSegment]) -> Vec<SampledSegment> {
    let mut out: Vec<SampledSegment> = Vec::new();
    let mut carried = 0.0;
    for p in pieces {
        let roll = wrap_roll(carried + p.roll);
        if p.length <= 0.0 {
            carried = roll;
            continue;
        }
        carried = 0.0;
        match out.last_mut() {
            Some(last) if last.kind == SegmentKind::Line && p.kind == SegmentKind::Line => {
                last.length += p.length;
                last.roll = wrap_roll(last.roll + roll);
            }
            Some(last)
                if last.kind == SegmentKind::Arc && p.kind == SegmentKind::Arc && roll == 0.0 =>
            {
                last.length += p.length;
            }
            _ => out.push(SampledSegment { roll, ..*p }),
        }
    }
    out
}

/// An angle in (-pi, pi], keeping 0 and pi exact (plane mode's rolls).
fn wrap_roll(a: f64) -> f64 {
    if a == 0.0 || a == PI {
        return a;
    }
    if a == -PI {
        return PI;
    }
    let w = a.rem_euclid(core::f64::consts::TAU);
    if w > PI {
        w - core::f64::consts::TAU
    } else {
        w
    }
}

/// What [`measure`] finds of a valid path.
#[derive(Clone, Copy, Debug)]
pub struct Measured {
    /// The tip at the end.
    pub end: Frame,
    /// Total length (mm).
    pub length: f64,
    /// Smallest clearance to any obstacle surface (mm).
    pub min_clearance: f64,
    /// Segments.
    pub count: usize,
}

/// Measures normalized `segments` from the insertion angles, or `None` when the path breaks a
/// limit: posture outside the cone, a segment longer than its bound, two lines in a row, more
/// than N segments, a roll other than 0 or pi in plane mode, or too little clearance.
pub fn measure(
    l: &Limits,
    theta1: f64,
    theta2: f64,
    segments: &[SampledSegment],
) -> Option<Measured> {
    if !l.posture_ok(theta1, theta2) || segments.len() > l.max_segments {
        return None;
    }
    let mut f = l.insertion(theta1, theta2);
    let (mut length, mut min_clearance) = (0.0, f64::INFINITY);
    for (i, s) in segments.iter().enumerate() {
        let lines_meet =
            i > 0 && s.kind == SegmentKind::Line && segments[i - 1].kind == SegmentKind::Line;
        let bad_roll = l.plane && s.roll != 0.0 && s.roll != PI;
        if lines_meet || bad_roll || !(0.0..=l.bound(s.kind)).contains(&s.length) {
            return None;
        }
        let g = l.roll(&f, s.roll);
        min_clearance = min_clearance.min(l.clearance_of(&g, s.kind, s.length));
        if min_clearance < l.clearance {
            return None;
        }
        f = l.advance(&g, s.kind, s.length);
        length += s.length;
    }
    Some(Measured {
        end: f,
        length,
        min_clearance,
        count: segments.len(),
    })
}

/// The tail a path of normalized `segments` ends with.
pub fn tail_of(segments: &[SampledSegment]) -> Tail {
    segments.last().map_or(Tail::START, |s| Tail {
        kind: Some(s.kind),
        run: s.length,
        count: segments.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(kind: SegmentKind, roll: f64, length: f64) -> SampledSegment {
        SampledSegment { kind, roll, length }
    }
    const R: SegmentKind = SegmentKind::Arc;
    const L: SegmentKind = SegmentKind::Line;

    #[test]
    fn pieces_merge_into_the_planners_segments() {
        let pieces = [
            seg(R, 0.5, 3.0),
            seg(R, 0.0, 2.0), // no roll: the same arc
            seg(L, 0.0, 4.0),
            seg(L, 0.25, 1.0), // a line after a line: one line, the rolls added
            seg(R, 0.75, 0.0), // empty: dropped, its roll carried on
            seg(R, 0.5, 6.0),
            seg(R, 0.1, 1.0), // a roll: a new segment
        ];
        assert_eq!(
            normalize(&pieces),
            vec![
                seg(R, 0.5, 5.0),
                seg(L, 0.25, 5.0),
                seg(R, 1.25, 6.0),
                seg(R, 0.1, 1.0)
            ]
        );
    }

    #[test]
    fn two_lines_in_a_row_and_too_many_segments_are_refused() {
        let mut s = planner_core::Scenario::paper();
        s.obstacles.clear();
        s.options.max_control_degree = 3;
        let l = Limits::new(&s);
        let ok = [seg(R, 0.0, 10.0), seg(L, 0.0, 10.0), seg(R, PI, 10.0)];
        assert_eq!(measure(&l, 0.0, 0.0, &ok).map(|m| m.count), Some(3));
        let lines = [seg(R, 0.0, 10.0), seg(L, 0.0, 10.0), seg(L, 0.0, 10.0)];
        assert!(measure(&l, 0.0, 0.0, &lines).is_none());
        let four = [ok.as_slice(), &[seg(L, 0.0, 1.0)]].concat();
        assert!(measure(&l, 0.0, 0.0, &four).is_none());
        // Plane mode: a roll other than 0 or pi leaves the plane.
        let tilted = [seg(R, 0.3, 10.0)];
        assert!(measure(&l, 0.0, 0.0, &tilted).is_none());
    }
}
