use super::*;

/// A small deterministic generator in [0, 1).
fn uniform(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
    (*state >> 8) as f32 / (1u32 << 24) as f32
}

/// The completions of `kinds` with `sides` from `pose` onto `(tx, 0)`.
fn completions(
    pose: Pose,
    kinds: (SegmentKind, SegmentKind),
    sides: (f32, f32),
    half_turn_at_most: (bool, bool),
    tx: f32,
    r: f32,
) -> heapless::Vec<(f32, f32), 4> {
    let tail = Tail {
        kinds,
        sides,
        half_turn_at_most,
    };
    let mut out = heapless::Vec::new();
    complete(
        pose,
        crate::fmath::sincos(pose.psi),
        &tail,
        tx,
        r,
        &mut |a, b| {
            out.push((a, b)).unwrap();
        },
    );
    out
}

/// Where the two segments of a completion end.
fn end_of(
    pose: Pose,
    kinds: (SegmentKind, SegmentKind),
    sides: (f32, f32),
    c: (f32, f32),
    r: f32,
) -> Pose {
    let mid = advance(pose, kinds.0, c.0, sides.0, r);
    advance(mid, kinds.1, c.1, sides.1, r)
}

fn close(got: (f32, f32), want: (f32, f32)) -> bool {
    (got.0 - want.0).abs() < 1e-3 && (got.1 - want.1).abs() < 1e-3
}

const R: f32 = 50.0;
const QUARTER: f32 = R * core::f32::consts::FRAC_PI_2;

#[test]
fn arc_then_line_is_the_tangent_from_the_circle() {
    // From (0, -80) along the chord, a left arc about (0, -30) turns a quarter circle to
    // (50, -30), heading across the chord; 30 mm of line reach the target at (50, 0).
    let pose = Pose {
        x: 0.0,
        y: -80.0,
        psi: 0.0,
    };
    let kinds = (SegmentKind::Arc, SegmentKind::Line);
    let found = completions(pose, kinds, (-1.0, 1.0), (true, false), 50.0, R);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(close(found[0], (QUARTER, 30.0)), "{found:?}");
    // A target inside the arc's circle has no tangent.
    let inside = Pose {
        x: 0.0,
        y: -20.0,
        psi: 0.0,
    };
    assert!(completions(inside, kinds, (-1.0, 1.0), (false, false), 10.0, R).is_empty());
}

#[test]
fn line_then_arc_has_both_roots_of_its_quadratic() {
    // From (0, -50) along the chord: 40 mm of line and a left quarter circle about (40, 0)
    // reach (90, 0); so do 140 mm and three quarters about (140, 0).
    let pose = Pose {
        x: 0.0,
        y: -50.0,
        psi: 0.0,
    };
    let kinds = (SegmentKind::Line, SegmentKind::Arc);
    let found = completions(pose, kinds, (1.0, -1.0), (false, false), 90.0, R);
    assert_eq!(found.len(), 2, "{found:?}");
    assert!(close(found[0], (40.0, QUARTER)), "{found:?}");
    assert!(close(found[1], (140.0, 3.0 * QUARTER)), "{found:?}");
    // An arc limited to half a circle keeps only the first.
    let limited = completions(pose, kinds, (1.0, -1.0), (false, true), 90.0, R);
    assert_eq!(limited.len(), 1);
    assert_eq!(limited[0], found[0]);
}

#[test]
fn arc_then_opposite_arc_meets_where_the_circles_touch() {
    // From (0, 100) along the chord: a right quarter circle about (0, 50) to (50, 50), then a
    // left one about (100, 50) to the target (100, 0), heading along the chord again.
    let pose = Pose {
        x: 0.0,
        y: 100.0,
        psi: 0.0,
    };
    let kinds = (SegmentKind::Arc, SegmentKind::Arc);
    let sides = (1.0, -1.0);
    let found = completions(pose, kinds, sides, (false, false), 100.0, R);
    assert_eq!(found.len(), 2, "{found:?}");
    assert!(
        found.iter().any(|&c| close(c, (QUARTER, QUARTER))),
        "{found:?}"
    );
    // Arcs to the same side lie on one circle: no completion.
    assert!(completions(pose, kinds, (1.0, 1.0), (false, false), 100.0, R).is_empty());
}

#[test]
fn every_completion_ends_on_the_target() {
    let mut rng = 5u32;
    let kinds = [
        (SegmentKind::Arc, SegmentKind::Line),
        (SegmentKind::Line, SegmentKind::Arc),
        (SegmentKind::Arc, SegmentKind::Arc),
    ];
    let mut ended = 0;
    for case in 0..600 {
        let pose = Pose {
            x: 100.0 * uniform(&mut rng) - 20.0,
            y: 100.0 * uniform(&mut rng) - 50.0,
            psi: 3.0 * uniform(&mut rng) - 1.5,
        };
        let sides = (
            if case % 2 == 0 { 1.0 } else { -1.0 },
            if case % 4 < 2 { -1.0 } else { 1.0 },
        );
        let k = kinds[case % 3];
        let tx = 60.0 + 60.0 * uniform(&mut rng);
        for c in completions(pose, k, sides, (false, false), tx, R) {
            let end = end_of(pose, k, sides, c, R);
            assert!(
                (end.x - tx).abs() < 1e-3 && end.y.abs() < 1e-3,
                "case {case}: {c:?} ends at ({}, {})",
                end.x,
                end.y
            );
            ended += 1;
        }
    }
    assert!(ended > 300, "only {ended} completions");
}

#[test]
fn completions_left_out_turn_past_half_a_circle() {
    let mut rng = 11u32;
    let r = 50.0;
    let kinds = [
        (SegmentKind::Arc, SegmentKind::Line),
        (SegmentKind::Line, SegmentKind::Arc),
        (SegmentKind::Arc, SegmentKind::Arc),
    ];
    let (mut kept, mut dropped) = (0, 0);
    for case in 0..6000 {
        let pose = Pose {
            x: 160.0 * uniform(&mut rng) - 40.0,
            y: 160.0 * uniform(&mut rng) - 80.0,
            psi: 7.0 * uniform(&mut rng) - 3.5,
        };
        let sc = crate::fmath::sincos(pose.psi);
        let k = kinds[case % 3];
        let sides = (
            if case % 2 == 0 { 1.0 } else { -1.0 },
            if case % 4 < 2 { -1.0 } else { 1.0 },
        );
        let tx = 40.0 + 80.0 * uniform(&mut rng);
        let completions = |half_turn_at_most| {
            let mut out = heapless::Vec::<(f32, f32), 4>::new();
            let tail = Tail {
                kinds: k,
                sides,
                half_turn_at_most,
            };
            complete(pose, sc, &tail, tx, r, &mut |a, b| {
                out.push((a, b)).unwrap();
            });
            out
        };
        let (all, some) = (completions((false, false)), completions((true, true)));
        // What is kept is kept bit for bit and in order; what is left out has an arc that
        // turns by more than half a circle (`emit` refuses it).
        let mut rest = all.iter();
        for c in &some {
            assert!(rest.any(|a| a.0.to_bits() == c.0.to_bits() && a.1.to_bits() == c.1.to_bits()));
        }
        for c in all.iter().filter(|c| !some.contains(c)) {
            let arc_a = k.0 == SegmentKind::Arc && c.0 > core::f32::consts::PI * r;
            let arc_b = k.1 == SegmentKind::Arc && c.1 > core::f32::consts::PI * r;
            assert!(arc_a || arc_b, "case {case}: {c:?} left out");
            dropped += 1;
        }
        kept += some.len();
    }
    // Both happen often enough for the test to mean something.
    assert!(
        kept > 500 && dropped > 1000,
        "kept {kept}, dropped {dropped}"
    );
}

#[test]
fn distance_matches_dense_sampling_of_the_segment() {
    let mut rng = 7u32;
    let radius = 50.0;
    for case in 0..400 {
        let kind = if case % 2 == 0 {
            SegmentKind::Arc
        } else {
            SegmentKind::Line
        };
        let side = if case % 4 < 2 { 1.0 } else { -1.0 };
        let start = Pose {
            x: 40.0 * uniform(&mut rng) - 20.0,
            y: 40.0 * uniform(&mut rng) - 20.0,
            psi: 6.0 * uniform(&mut rng) - 3.0,
        };
        let len = 2.0 * core::f32::consts::PI * radius * uniform(&mut rng);
        let q = (
            300.0 * uniform(&mut rng) - 150.0,
            300.0 * uniform(&mut rng) - 150.0,
        );
        let exact =
            crate::fmath::sqrt(Drawn::new(start, kind, len, side, radius).distance_squared(q));
        let samples = 20_000;
        let sampled = (0..=samples)
            .map(|k| {
                let at = advance(start, kind, len * k as f32 / samples as f32, side, radius);
                crate::fmath::sqrt((q.0 - at.x).powi(2) + (q.1 - at.y).powi(2))
            })
            .fold(f32::INFINITY, f32::min);
        // Sampling overestimates by at most half a step squared over the distance.
        assert!(
            exact <= sampled + 1e-3 && sampled - exact < 0.05,
            "case {case}: exact {exact}, sampled {sampled}"
        );
    }
}
