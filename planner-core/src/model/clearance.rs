//! Exact shortest distances from a point (an obstacle's centre) to an arc or a line segment.
//!
//! Closed forms, no sampling: a line segment clamps the projection; an arc projects the point on
//! its circle's plane, and the nearest point of the whole circle is on the arc or else one of the
//! two ends is nearest (the distance to a circle point is unimodal in the angle).

use crate::model::form::SegmentKind;
use crate::model::kinematics::{Frame, V3};

/// Where on a segment the nearest point lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Nearest {
    /// At the segment's start.
    Start,
    /// Strictly inside.
    Interior,
    /// At the segment's end.
    End,
}

/// The nearest point of a segment to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Distance (mm).
    pub distance: f32,
    /// The nearest point of the segment.
    pub point: V3,
    /// Arc length from the segment's start to `point`.
    pub at: f32,
    /// Start, interior or end.
    pub where_: Nearest,
}

const TWO_PI: f32 = core::f32::consts::TAU;

/// Nearest point of the segment (`kind`, `length`, arcs of `radius`) starting at `start` to `c`.
pub fn closest(start: &Frame, kind: SegmentKind, length: f32, radius: f32, c: &V3) -> Closest {
    match kind {
        SegmentKind::Line => closest_on_line(start, length, c),
        SegmentKind::Arc => closest_on_arc(start, length, radius, c, None),
    }
}

/// [`closest`] for a segment of a drawn path, whose end point `end` is known (an arc's end is
/// then not drawn again: the same point, so the same result bit for bit).
pub fn closest_drawn(
    start: &Frame,
    end: &V3,
    kind: SegmentKind,
    length: f32,
    radius: f32,
    c: &V3,
) -> Closest {
    match kind {
        SegmentKind::Line => closest_on_line(start, length, c),
        SegmentKind::Arc => closest_on_arc(start, length, radius, c, Some(end)),
    }
}

fn finish(point: V3, c: &V3, at: f32, where_: Nearest) -> Closest {
    let d = point - c;
    Closest {
        distance: crate::fmath::sqrt(d.dot(&d)),
        point,
        at,
        where_,
    }
}

fn closest_on_line(start: &Frame, length: f32, c: &V3) -> Closest {
    let e3 = start.e3();
    let t = (c - start.p).dot(&e3);
    if t <= 0.0 {
        finish(start.p, c, 0.0, Nearest::Start)
    } else if t >= length {
        finish(start.p + e3 * length, c, length, Nearest::End)
    } else {
        finish(start.p + e3 * t, c, t, Nearest::Interior)
    }
}

fn closest_on_arc(start: &Frame, length: f32, radius: f32, c: &V3, end: Option<&V3>) -> Closest {
    let (e2, e3) = (start.e2(), start.e3());
    let center = start.p + e2 * radius;
    let q = c - center;
    // Circle points are center + radius (-cos a e2 + sin a e3), a = arc length / radius.
    let (qx, qy) = (q.dot(&e2), q.dot(&e3));
    let sweep = length / radius;
    let mut a0 = if qx == 0.0 && qy == 0.0 {
        0.0 // on the circle's axis every point is as near: take the start
    } else {
        crate::fmath::atan2(qy, -qx)
    };
    if a0 < 0.0 {
        a0 += TWO_PI;
    }
    if a0 <= 0.0 {
        return finish(start.p, c, 0.0, Nearest::Start);
    }
    if a0 < sweep {
        let (sn, cs) = crate::fmath::sincos(a0);
        let p = center + (e2 * -cs + e3 * sn) * radius;
        return finish(p, c, a0 * radius, Nearest::Interior);
    }
    let at_start = finish(start.p, c, 0.0, Nearest::Start);
    let end = match end {
        Some(end) => *end,
        None => start.advanced(SegmentKind::Arc, length, radius).p,
    };
    let at_end = finish(end, c, length, Nearest::End);
    if at_end.distance <= at_start.distance {
        at_end
    } else {
        at_start
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::kinematics::{entry_basis, insertion_frame};
    use proptest::prelude::*;

    fn frame(t1: f32, t2: f32, roll: f32) -> Frame {
        insertion_frame(
            V3::new(1.0, -2.0, 3.0),
            &entry_basis([0.2, 0.1, 1.0]),
            t1,
            t2,
        )
        .rolled(roll)
    }

    fn sampled(start: &Frame, kind: SegmentKind, len: f32, radius: f32, c: &V3) -> f32 {
        let n = 20_000;
        (0..=n)
            .map(|k| {
                let t = len * k as f32 / n as f32;
                (start.point_at(kind, t, radius) - c).norm()
            })
            .fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn point_on_the_circle_axis_is_radius_away() {
        let f = frame(0.0, 0.0, 0.0);
        let c = f.p + f.e2() * 40.0 + f.e1() * 30.0;
        let got = closest(&f, SegmentKind::Arc, 60.0, 40.0, &c);
        assert!((got.distance - 50.0).abs() < 1e-3);
    }

    proptest! {
        #[test]
        fn exact_distance_matches_dense_sampling(
            t1 in -1.0f32..1.0, t2 in -1.0f32..1.0, roll in -3.2f32..3.2,
            arc in any::<bool>(), len in 0.0f32..300.0, radius in 10.0f32..100.0,
            cx in -150.0f32..150.0, cy in -150.0f32..150.0, cz in -150.0f32..150.0,
        ) {
            let f = frame(t1, t2, roll);
            let kind = if arc { SegmentKind::Arc } else { SegmentKind::Line };
            let c = V3::new(cx, cy, cz);
            let exact = closest(&f, kind, len, radius, &c);
            let end = f.advanced(kind, len, radius).p;
            prop_assert_eq!(closest_drawn(&f, &end, kind, len, radius, &c), exact);
            let brute = sampled(&f, kind, len, radius, &c);
            // Sampling can only overestimate; its step is at most 300/20000 mm.
            prop_assert!(exact.distance <= brute + 2e-3, "exact {} brute {}", exact.distance, brute);
            prop_assert!(exact.distance >= brute - 0.02 - 1e-4 * brute, "exact {} brute {}", exact.distance, brute);
            // The reported point is on the segment at the reported arc length.
            let on = f.point_at(kind, exact.at, radius);
            prop_assert!((on - exact.point).norm() < 1e-3 * (1.0 + len));
        }
    }
}
