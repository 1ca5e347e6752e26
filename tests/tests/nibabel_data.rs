//! `needle cover` on nibabel's own test data (its wheel's `nibabel/tests/data`, from the venv
//! `scripts/python-env` makes; `tests/python/nibabel_data.py`): `anatomical.nii`, a 2 mm head
//! scan stored big-endian with its x axis flipped, thresholded into two labels and saved by
//! nibabel with the scan's own header; and `standard.nii.gz` as shipped (uint8, voxels 1 x 3 x 2
//! mm). Every corner of every labelled voxel, placed by nibabel's own affine, lies inside the
//! cover (checked exhaustively), and a one-sphere cover sits on the box of those corners.

use needle_e2e::label_files::cover_spheres;
use needle_e2e::{needle_json, venv_script};
use serde_json::Value;

type Sphere = (i64, [f64; 3], f64);
/// Rows of a 4 x 4 affine.
type Affine = Vec<Vec<f64>>;
/// Each label's voxels (i, j, k).
type Voxels = Vec<(i64, Vec<Vec<i64>>)>;

/// nibabel's affine (4 x 4 rows) applied to grid point `g`.
fn world(affine: &[Vec<f64>], g: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| (0..3).map(|c| affine[r][c] * g[c]).sum::<f64>() + affine[r][3])
}

/// The eight corners of voxel `v`, in the world by `affine`.
fn corners(affine: &[Vec<f64>], v: &[i64]) -> Vec<[f64; 3]> {
    (0..8)
        .map(|c| {
            let g: [f64; 3] =
                std::array::from_fn(|k| v[k] as f64 + if c >> k & 1 == 1 { 0.5 } else { -0.5 });
            world(affine, g)
        })
        .collect()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// What the Python side printed for one file: nibabel's affine and each label's voxels.
fn affine_and_labels(v: &Value) -> (Affine, Voxels) {
    let affine = serde_json::from_value(v["affine"].clone()).unwrap();
    let labels = v["labels"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(l, vox)| {
            (
                l.parse().unwrap(),
                serde_json::from_value(vox.clone()).unwrap(),
            )
        })
        .collect();
    (affine, labels)
}

/// Every corner of every voxel of each label inside a sphere of that label's cover; returns
/// the number of corners checked.
fn every_corner_covered(v: &Value, spheres: &[Sphere]) -> usize {
    let (affine, labels) = affine_and_labels(v);
    let mut checked = 0;
    for (label, voxels) in &labels {
        assert!(!voxels.is_empty(), "label {label} has no voxels");
        let own: Vec<&Sphere> = spheres.iter().filter(|s| s.0 == *label).collect();
        assert!(!own.is_empty(), "label {label} has no cover");
        for vox in voxels {
            for p in corners(&affine, vox) {
                assert!(
                    own.iter().any(|s| dist(p, s.1) <= s.2 + 1e-6),
                    "label {label}: corner {p:?} of voxel {vox:?} outside the cover"
                );
                checked += 1;
            }
        }
    }
    checked
}

/// A label covered by one sphere: it sits on the centre of the world box of the label's voxel
/// corners (placed by nibabel's affine) and reaches the farthest corner, to 1e-4 mm.
fn one_sphere_on_the_corners_box(v: &Value, label: i64, s: &Sphere) {
    let (affine, labels) = affine_and_labels(v);
    let (_, voxels) = labels.iter().find(|l| l.0 == label).unwrap();
    let all: Vec<[f64; 3]> = voxels.iter().flat_map(|v| corners(&affine, v)).collect();
    let centre: [f64; 3] = std::array::from_fn(|k| {
        let lo = all.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let hi = all.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        (lo + hi) / 2.0
    });
    let radius = all.iter().map(|p| dist(*p, centre)).fold(0.0, f64::max);
    assert!(
        dist(s.1, centre) < 1e-4,
        "{s:?}: nibabel's box centre {centre:?}"
    );
    assert!(
        (s.2 - radius).abs() < 1e-4,
        "{s:?}: nibabel's radius {radius}"
    );
}

#[test]
fn nibabel_test_data_is_covered_corner_by_corner() {
    let dir = std::env::temp_dir().join(format!("needle-nibabel-data-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let info: Value = serde_json::from_slice(&venv_script("nibabel_data.py", &[&dir])).unwrap();
    let scan = &info["anatomical"];
    // Big-endian int16 with a flipped x axis: both must be read as nibabel reads them.
    assert_eq!(scan["dtype"], ">i2");
    assert_eq!(scan["affine"][0][0], -2.0);
    let file = scan["file"].as_str().unwrap();
    let cover = cover_spheres(&needle_json(&["cover", file, "--json"]));
    let checked = every_corner_covered(scan, &cover);
    assert!(checked > 8 * 20_000, "{checked}");
    let one = cover_spheres(&needle_json(&[
        "cover",
        file,
        "--labels",
        "2",
        "--max-spheres",
        "1",
        "--tightness",
        "1e9",
        "--json",
    ]));
    assert_eq!(one.len(), 1);
    one_sphere_on_the_corners_box(scan, 2, &one[0]);

    let standard = &info["standard"];
    assert_eq!(standard["affine"][1][1], 3.0);
    let file = standard["file"].as_str().unwrap();
    let cover = cover_spheres(&needle_json(&["cover", file, "--json"]));
    assert!(every_corner_covered(standard, &cover) == 8 * 30);
    let one = cover_spheres(&needle_json(&[
        "cover",
        file,
        "--max-spheres",
        "1",
        "--tightness",
        "1e9",
        "--json",
    ]));
    assert_eq!(one.len(), 1);
    one_sphere_on_the_corners_box(standard, 255, &one[0]);
    let _ = std::fs::remove_dir_all(&dir);
}
