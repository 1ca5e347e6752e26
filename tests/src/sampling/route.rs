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
