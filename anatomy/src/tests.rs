//! Covers of label maps made here: a ball, two touching boxes, a thin curved tube and a hollow
//! shell, on isotropic, anisotropic and oblique grids.

use super::cover::{
    cover_segment, ladder, uncovered_corners, uncovered_voxels, CoverOptions, Reach, Sphere,
};
use super::label_map::{LabelMap, Segment};

/// A map of `dims` voxels whose label at (i, j, k) is `f(i, j, k)`.
fn map_of(
    dims: [usize; 3],
    ijk_to_ras: [[f64; 4]; 3],
    f: impl Fn(i64, i64, i64) -> i64,
) -> LabelMap {
    let mut labels = Vec::with_capacity(dims.iter().product());
    for k in 0..dims[2] as i64 {
        for j in 0..dims[1] as i64 {
            for i in 0..dims[0] as i64 {
                labels.push(f(i, j, k));
            }
        }
    }
    LabelMap {
        dims,
        labels,
        ijk_to_ras,
        named: Vec::new(),
    }
    .validated()
    .unwrap()
}

fn scaled(s: [f64; 3], origin: [f64; 3]) -> [[f64; 4]; 3] {
    [
        [s[0], 0.0, 0.0, origin[0]],
        [0.0, s[1], 0.0, origin[1]],
        [0.0, 0.0, s[2], origin[2]],
    ]
}

const OPTIONS: CoverOptions = CoverOptions {
    margin_mm: 0.0,
    max_spheres: 64,
    tightness: 3.0,
};

fn segment(label: i64) -> Segment {
    Segment {
        name: format!("label {label}"),
        label,
    }
}

/// A ball of radius 9 voxels: one sphere, no more than one voxel larger than the ball.
#[test]
fn a_ball_is_one_sphere_hardly_larger_than_the_ball() {
    let r = 9.0;
    let map = map_of([25, 25, 25], scaled([1.0; 3], [0.0; 3]), |i, j, k| {
        let d = [i, j, k].map(|x| x as f64 - 12.0);
        i64::from((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= r)
    });
    let c = cover_segment(&map, &segment(1), &OPTIONS).unwrap();
    assert_eq!(c.spheres.len(), 1, "{:?}", c.spheres);
    let s = c.spheres[0];
    assert!(s.radius <= r + 1.0, "{}", s.radius);
    assert!(s.center.iter().all(|&x| (x - 12.0).abs() < 1e-9));
    assert_eq!(uncovered_corners(&map, &map.voxels_of(1), &c.spheres), 0);
    assert!(c.outside_ratio < 0.5 && c.farthest_mm <= 1.5, "{c:?}");
}

/// Two boxes that touch, on anisotropic voxels: each covered on its own, every corner inside.
#[test]
fn two_touching_boxes_are_covered_apart() {
    let map = map_of(
        [30, 16, 12],
        scaled([0.5, 0.8, 2.0], [-3.0, 4.0, 10.0]),
        |i, j, k| {
            let inside = (2..14).contains(&j) && (2..10).contains(&k);
            match i {
                2..=13 if inside => 1,
                14..=27 if inside => 2,
                _ => 0,
            }
        },
    );
    for label in [1, 2] {
        let c = cover_segment(&map, &segment(label), &OPTIONS).unwrap();
        assert_eq!(
            uncovered_corners(&map, &map.voxels_of(label), &c.spheres),
            0
        );
        assert!(c.outside_ratio < 2.0, "label {label}: {c:?}");
    }
}

/// A thin tube bent in a quarter circle: a chain of spheres, much tighter than one sphere.
#[test]
fn a_thin_curved_tube_becomes_a_chain() {
    let map = map_of([48, 48, 9], scaled([1.0; 3], [0.0; 3]), |i, j, k| {
        let (x, y, z) = (i as f64, j as f64, k as f64 - 4.0);
        let off = ((x * x + y * y).sqrt() - 40.0).hypot(z);
        i64::from(off <= 2.0)
    });
    let c = cover_segment(&map, &segment(1), &OPTIONS).unwrap();
    assert!(c.spheres.len() >= 8, "{}", c.spheres.len());
    assert_eq!(uncovered_corners(&map, &map.voxels_of(1), &c.spheres), 0);
    let one = CoverOptions {
        max_spheres: 1,
        tightness: 1e9,
        ..OPTIONS
    };
    let single = cover_segment(&map, &segment(1), &one).unwrap();
    assert!(
        c.outside_ratio * 10.0 < single.outside_ratio,
        "{} {}",
        c.outside_ratio,
        single.outside_ratio
    );
    // Too few spheres for that tightness: a clear error, not a looser cover.
    let few = CoverOptions {
        max_spheres: 3,
        ..OPTIONS
    };
    let err = cover_segment(&map, &segment(1), &few)
        .unwrap_err()
        .to_string();
    assert!(err.contains("needs more than 3 spheres"), "{err}");
}

/// A hollow shell, on an oblique grid (rotated 30° about z), with a margin: every voxel whole
/// inside one sphere with the margin to spare, and the cover follows the shell (far tighter than
/// the one sphere around it).
#[test]
fn a_hollow_shell_on_an_oblique_grid_is_covered_with_its_margin() {
    let (c30, s30) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let a = [
        [1.2 * c30, -1.2 * s30, 0.0, 5.0],
        [1.2 * s30, 1.2 * c30, 0.0, -7.0],
        [0.0, 0.0, 1.5, 2.0],
    ];
    let map = map_of([24, 24, 24], a, |i, j, k| {
        let d = [i, j, k].map(|x| x as f64 - 11.5);
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        i64::from((8.0..=10.0).contains(&r))
    });
    let voxels = map.voxels_of(1);
    for margin in [0.0, 1.5] {
        let o = CoverOptions {
            margin_mm: margin,
            max_spheres: 512,
            ..OPTIONS
        };
        let c = cover_segment(&map, &segment(1), &o).unwrap();
        assert_eq!(uncovered_voxels(&map, &voxels, &c.spheres, margin), 0);
        assert!(c.tight_enough, "{margin}: {}", c.outside_dilated_ratio);
        assert!(
            c.outside_dilated_ratio <= 2.0,
            "{}",
            c.outside_dilated_ratio
        );
        // Shrunk by a little more than the margin, some voxel is no longer held: the margin is
        // in every sphere, not more.
        let less: Vec<_> = c
            .spheres
            .iter()
            .map(|s| Sphere {
                radius: s.radius - 0.01,
                ..*s
            })
            .collect();
        assert!(uncovered_voxels(&map, &voxels, &less, margin) > 0);
    }
}

/// A label nothing carries, and a map whose axes do not span 3-D, are errors.
#[test]
fn an_empty_segment_and_a_singular_affine_are_errors() {
    let map = map_of([4, 4, 4], scaled([1.0; 3], [0.0; 3]), |i, _, _| {
        i64::from(i == 1)
    });
    let err = cover_segment(&map, &segment(7), &OPTIONS)
        .unwrap_err()
        .to_string();
    assert!(err.contains("has no voxels"), "{err}");
    let flat = LabelMap {
        ijk_to_ras: scaled([1.0, 1.0, 0.0], [0.0; 3]),
        ..map
    };
    let err = flat.validated().unwrap_err().to_string();
    assert!(err.contains("singular"), "{err}");
}

/// The deepest point of a ball is its centre, at its radius from the outside; of a box on
/// anisotropic voxels, its middle, at half its thinnest side (to the nearest outside voxel
/// centre); both checked against a brute-force search.
#[test]
fn the_deepest_point_is_the_farthest_from_the_outside() {
    use super::interior::deepest_point;
    let ball = map_of(
        [21, 21, 21],
        scaled([1.0; 3], [5.0, -2.0, 7.0]),
        |i, j, k| {
            let d = [i, j, k].map(|x| x as f64 - 10.0);
            i64::from((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= 7.5)
        },
    );
    let (p, depth) = deepest_point(&ball, 1).unwrap();
    assert_eq!(p, [15.0, 8.0, 17.0]);
    let brute = |map: &LabelMap, label: i64| {
        let voxels = map.voxels_of(label);
        let [ni, nj, nk] = map.dims.map(|d| d as i64);
        let mut outside = Vec::new();
        for k in -1..=nk {
            for j in -1..=nj {
                for i in -1..=ni {
                    if map.at(i, j, k) != label {
                        outside.push(map.world([i, j, k].map(|x| x as f64)));
                    }
                }
            }
        }
        voxels
            .iter()
            .map(|v| {
                let p = map.world(v.map(|x| x as f64));
                outside
                    .iter()
                    .map(|q| {
                        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2))
                            .sqrt()
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0f64, f64::max)
    };
    assert!((depth - brute(&ball, 1)).abs() < 1e-9, "{depth}");
    let boxy = map_of([20, 14, 9], scaled([0.5, 0.8, 2.0], [0.0; 3]), |i, j, k| {
        i64::from((2..18).contains(&i) && (2..12).contains(&j) && (1..8).contains(&k))
    });
    let (_, depth) = deepest_point(&boxy, 1).unwrap();
    assert!((depth - brute(&boxy, 1)).abs() < 1e-9, "{depth}");
    assert!((depth - 4.0).abs() < 1e-9, "{depth}");
    assert!(deepest_point(&boxy, 3).is_err());
}

fn holds(spheres: &[Sphere], p: [f64; 3]) -> bool {
    spheres.iter().any(|s| {
        let d: f64 = (0..3).map(|k| (p[k] - s.center[k]).powi(2)).sum();
        d.sqrt() <= s.radius
    })
}

/// A bar 80 mm long whose far half no path of 40 mm can reach: that half takes coarse spheres,
/// so the cover takes fewer than without a reach, and still holds every voxel whole.
#[test]
fn spheres_beyond_the_needles_reach_are_coarse() {
    let map = map_of([80, 8, 8], scaled([1.0; 3], [0.0; 3]), |_, _, _| 1);
    let o = CoverOptions {
        margin_mm: 1.0,
        max_spheres: 512,
        tightness: 1.3,
    };
    let reach = Reach {
        entry: [0.0, 20.0, 4.0],
        target: [10.0, 20.0, 4.0],
        length: 40.0,
    };
    let fine = ladder(&map, &segment(1), &o, None).unwrap();
    let near = ladder(&map, &segment(1), &o, Some(&reach)).unwrap();
    let (fine, near) = (
        fine.candidates.last().unwrap(),
        near.candidates.last().unwrap(),
    );
    let voxels = map.voxels_of(1);
    assert_eq!(uncovered_voxels(&map, &voxels, &near.spheres, 1.0), 0);
    let beyond = near
        .spheres
        .iter()
        .filter(|s| reach.misses(s.center, s.radius));
    assert!(beyond.count() > 0);
    assert!(
        near.spheres.len() < fine.spheres.len(),
        "{} against {}",
        near.spheres.len(),
        fine.spheres.len()
    );
}

/// A target 2.5 mm from a cube's face lies inside the one sphere a tightness of 3 allows; a
/// scenario's cover keeps it outside, holding every voxel still.
#[test]
fn a_target_near_a_segment_is_kept_outside_its_cover() {
    let map = map_of([20, 20, 20], scaled([1.0; 3], [0.0; 3]), |i, j, k| {
        i64::from([i, j, k].iter().all(|x| (5..15).contains(x)))
    });
    let o = CoverOptions {
        margin_mm: 0.5,
        max_spheres: 512,
        tightness: 3.0,
    };
    // The cube's face is at x = 14.5.
    let target = [14.5 + 2.5, 9.5, 9.5];
    let loose = cover_segment(&map, &segment(1), &o).unwrap();
    assert!(holds(&loose.spheres, target));
    let reach = Reach {
        entry: [60.0, 9.5, 9.5],
        target,
        length: 200.0,
    };
    let l = ladder(&map, &segment(1), &o, Some(&reach)).unwrap();
    let kept = l.candidates.last().unwrap();
    assert!(!holds(&kept.spheres, target));
    assert_eq!(uncovered_voxels(&map, &l.voxels, &kept.spheres, 0.5), 0);
}

/// Segments that meet at a face or only at a corner are one group; one a voxel apart is not;
/// a label not chosen joins nothing. Groups keep the order given.
#[test]
fn touching_segments_are_grouped_and_apart_ones_not() {
    use super::touching::touching_groups;
    let map = map_of([12, 6, 6], scaled([1.0; 3], [0.0; 3]), |i, j, k| {
        match (i, j, k) {
            (0..=1, 0..=1, 0..=1) => 1,
            (2, 2, 2) => 2,     // meets label 1 at a corner only
            (3..=4, 2, 2) => 3, // meets label 2 at a face
            (6..=7, _, _) => 4, // a voxel apart from label 3
            (8, 0, 0) => 5,     // meets label 4, but is not chosen
            (9, 0, 0) => 6,     // meets only label 5
            _ => 0,
        }
    });
    let chosen: Vec<Segment> = [6, 4, 1, 3, 2].map(segment).to_vec();
    assert_eq!(
        touching_groups(&map, &chosen),
        vec![vec![0], vec![1], vec![2, 3, 4]]
    );
}

/// A capsule wrapped round its organ: covered with it as one solid, the pair takes far fewer
/// spheres than the capsule alone, and every voxel of both is held with the margin.
#[test]
fn a_capsule_with_its_organ_is_covered_as_one_solid() {
    use super::cover::group_ladder;
    let map = map_of([26, 26, 26], scaled([1.0; 3], [0.0; 3]), |i, j, k| {
        let d = [i, j, k].map(|x| x as f64 - 12.5);
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if r <= 9.0 {
            1
        } else if r <= 10.5 {
            2
        } else {
            0
        }
    });
    let o = CoverOptions {
        margin_mm: 1.0,
        max_spheres: 512,
        tightness: 1.5,
    };
    let capsule = ladder(&map, &segment(2), &o, None).unwrap();
    let both = group_ladder(&map, &[segment(1), segment(2)], &o, None).unwrap();
    let spheres = |l: &super::cover::Ladder| l.candidates.last().unwrap().spheres.clone();
    let (alone, together) = (spheres(&capsule), spheres(&both));
    assert!(
        together.len() * 4 < alone.len(),
        "{} spheres together, {} for the capsule alone",
        together.len(),
        alone.len()
    );
    for label in [1, 2] {
        assert_eq!(
            uncovered_voxels(&map, &map.voxels_of(label), &together, 1.0),
            0
        );
    }
}
