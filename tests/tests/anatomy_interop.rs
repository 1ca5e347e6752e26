//! `needle cover` on label maps written by implementations nobody here wrote: NIfTI by nibabel
//! and NRRD by pynrrd (in LPS raw and in RAS gzip), from the venv `scripts/python-env` makes
//! (`tests/python/label_maps.py`; nibabel's own test files: `nibabel_data.rs`). The three files
//! hold the same anatomy: the same spheres to 1e-4 mm, the ball one sphere on its centre, hardly
//! larger than the ball.

use needle_e2e::label_files::cover_spheres;
use needle_e2e::{needle_json, venv_script};
use serde_json::Value;

fn spheres(v: &Value) -> Vec<(i64, [f64; 3], f64)> {
    let mut out = cover_spheres(v);
    // In a fixed order: a float32 affine (NIfTI's) and a float64 one (NRRD's) can order spheres
    // of equal looseness differently.
    let key = |s: &(i64, [f64; 3], f64)| (s.0, s.1.map(|x| (x * 1e3).round() as i64));
    out.sort_by_key(key);
    out
}

#[test]
fn nibabel_and_pynrrd_maps_give_the_same_spheres() {
    let dir = std::env::temp_dir().join(format!("needle-anatomy-interop-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    venv_script("label_maps.py", &[&dir]);
    let covers: Vec<Vec<(i64, [f64; 3], f64)>> = ["map.nii.gz", "map-lps.nrrd", "map-ras.nrrd"]
        .iter()
        .map(|f| {
            spheres(&needle_json(&[
                "cover",
                dir.join(f).to_str().unwrap(),
                "--json",
            ]))
        })
        .collect();
    let first = &covers[0];
    let ball: Vec<_> = first.iter().filter(|s| s.0 == 1).collect();
    assert_eq!(ball.len(), 1, "{first:?}");
    // The ball's centre: voxel (11, 12, 10) of 0.7 x 0.9 x 1.2 mm from (-20, 15, 40).
    let centre = [-20.0 + 7.7, 15.0 + 10.8, 40.0 + 12.0];
    for (got, want) in ball[0].1.iter().zip(centre) {
        assert!((got - want).abs() < 1e-4, "{ball:?}");
    }
    let half_diagonal = (0.7f64.powi(2) + 0.9f64.powi(2) + 1.2f64.powi(2)).sqrt() / 2.0;
    assert!(ball[0].2 <= 7.0 + half_diagonal + 1e-9, "{ball:?}");
    assert!(first.iter().any(|s| s.0 == 2));
    for other in &covers[1..] {
        assert_eq!(other.len(), first.len());
        for (a, b) in other.iter().zip(first) {
            assert_eq!(a.0, b.0);
            for (x, y) in a.1.iter().zip(&b.1) {
                assert!((x - y).abs() < 1e-4, "{a:?} {b:?}");
            }
            assert!((a.2 - b.2).abs() < 1e-4, "{a:?} {b:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
