//! `needle cover` on label map files written by the tests (NRRD raw and gzip, LPS and RAS, a
//! Slicer segmentation with names, NIfTI-1): the same anatomy gives the same spheres whatever the
//! file, the spheres join a scenario that plans, and bad files and selections are clear errors.

use needle_e2e::label_files::{cover_spheres, write_nifti, write_nrrd, Labels, NrrdStyle};
use needle_e2e::{example, needle, needle_json};
use serde_json::Value;
use std::path::PathBuf;

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-cover-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A ball (label 1) and a box (label 2) on anisotropic voxels, placed at `origin` (RAS, mm).
fn anatomy(origin: [f64; 3]) -> Labels {
    let a = [
        [0.8, 0.0, 0.0, origin[0]],
        [0.0, 0.9, 0.0, origin[1]],
        [0.0, 0.0, 1.25, origin[2]],
    ];
    Labels::of([30, 28, 20], a, |i, j, k| {
        let d = [
            (i - 10) as f64 * 0.8,
            (j - 12) as f64 * 0.9,
            (k - 8) as f64 * 1.25,
        ];
        if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= 6.0 {
            1
        } else if (22..28).contains(&i) && (4..24).contains(&j) && (3..17).contains(&k) {
            2
        } else {
            0
        }
    })
}

/// The same anatomy as NRRD in LPS (raw), NRRD in RAS (gzip) and NIfTI (RAS): the same spheres
/// to 1e-4 mm, every segment covered, the ball by one sphere.
#[test]
fn lps_ras_and_nifti_give_the_same_spheres() {
    let dir = scratch("frames");
    let m = anatomy([-12.0, 20.0, 35.0]);
    let lps = dir.join("lps.nrrd");
    let ras = dir.join("ras.nrrd");
    let nii = dir.join("map.nii");
    let style = |space, gzip| NrrdStyle {
        space,
        gzip,
        pairs: &[],
    };
    write_nrrd(&lps, &m, &style("left-posterior-superior", false));
    write_nrrd(&ras, &m, &style("right-anterior-superior", true));
    write_nifti(&nii, &m);
    let runs: Vec<Value> = [&lps, &ras, &nii]
        .iter()
        .map(|p| needle_json(&["cover", p.to_str().unwrap(), "--json"]))
        .collect();
    let first = cover_spheres(&runs[0]);
    assert_eq!(runs[0]["frame"], "RAS");
    let labels: Vec<i64> = first.iter().map(|s| s.0).collect();
    assert_eq!(labels.iter().filter(|l| **l == 1).count(), 1, "{first:?}");
    assert!(labels.contains(&2));
    // The ball's sphere sits on the ball's centre, in RAS.
    let ball = first.iter().find(|s| s.0 == 1).unwrap();
    let centre = [-12.0 + 8.0, 20.0 + 10.8, 35.0 + 10.0];
    for (got, want) in ball.1.iter().zip(centre) {
        assert!((got - want).abs() < 1e-4, "{ball:?}");
    }
    assert!(ball.2 <= 6.0 + 1.25, "{ball:?}");
    for other in &runs[1..] {
        let s = cover_spheres(other);
        assert_eq!(s.len(), first.len());
        for (a, b) in s.iter().zip(&first) {
            assert_eq!(a.0, b.0);
            for (x, y) in a.1.iter().zip(&b.1) {
                assert!((x - y).abs() < 1e-4, "{a:?} {b:?}");
            }
            assert!((a.2 - b.2).abs() < 1e-4);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A Slicer segmentation names its segments: `--segments` selects by name, the names come back,
/// and `--out --scenario` appends the spheres to a scenario that still plans (the anatomy lies
/// far from the path: the same form, nearly the same length; D, the mean of 1/clearance over the
/// obstacles, counts them all).
#[test]
fn named_segments_are_selected_and_join_a_scenario() {
    let dir = scratch("named");
    let seg = dir.join("anatomy.seg.nrrd");
    let pairs = [
        ("Segment0_Name", "lesion"),
        ("Segment0_LabelValue", "1"),
        ("Segment1_Name", "rib"),
        ("Segment1_LabelValue", "2"),
    ];
    let style = NrrdStyle {
        space: "left-posterior-superior",
        gzip: true,
        pairs: &pairs,
    };
    write_nrrd(&seg, &anatomy([300.0, 300.0, 300.0]), &style);
    let out = dir.join("with-rib.toml");
    let space = example("space");
    let v = needle_json(&[
        "cover",
        seg.to_str().unwrap(),
        "--segments",
        "rib",
        "--margin",
        "1",
        "--json",
        "--out",
        out.to_str().unwrap(),
        "--scenario",
        space.to_str().unwrap(),
    ]);
    let segs = v["segments"].as_array().unwrap();
    assert_eq!(segs.len(), 1);
    assert_eq!(segs[0]["name"], "rib");
    assert_eq!(segs[0]["label"], 2);
    let base = needle_json(&["plan", space.to_str().unwrap(), "--json"]);
    let with = needle_json(&["plan", out.to_str().unwrap(), "--json"]);
    assert_eq!(with["best"]["form"], base["best"]["form"]);
    let length = |v: &Value| v["best"]["length"].as_f64().unwrap();
    assert!((length(&with) - length(&base)).abs() < 0.5);
    let count = |p: &PathBuf| {
        std::fs::read_to_string(p)
            .unwrap()
            .matches("[[obstacles]]")
            .count()
    };
    let added = segs[0]["spheres"].as_array().unwrap().len();
    assert_eq!(count(&out), count(&space) + added);
    let _ = std::fs::remove_dir_all(&dir);
}

fn error_of(args: &[&str]) -> String {
    let out = needle().args(args).output().unwrap();
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// Files that are not what they say, selections the map cannot give, and covers over their
/// sphere budget: errors naming the file and the problem.
#[test]
fn bad_files_and_selections_are_clear_errors() {
    let dir = scratch("bad");
    let fake = dir.join("fake.nrrd");
    std::fs::write(&fake, "this is not a label map\n").unwrap();
    let err = error_of(&["cover", fake.to_str().unwrap()]);
    assert!(
        err.contains("fake.nrrd") && err.contains("not a NRRD file"),
        "{err}"
    );
    let fake_nii = dir.join("fake.nii");
    std::fs::write(&fake_nii, vec![7u8; 400]).unwrap();
    let err = error_of(&["cover", fake_nii.to_str().unwrap()]);
    assert!(
        err.contains("fake.nii") && err.contains("not a NIfTI-1 file"),
        "{err}"
    );
    let good = dir.join("map.nrrd");
    let style = NrrdStyle {
        space: "right-anterior-superior",
        gzip: false,
        pairs: &[],
    };
    write_nrrd(&good, &anatomy([0.0; 3]), &style);
    let err = error_of(&["cover", good.to_str().unwrap(), "--labels", "9"]);
    assert!(
        err.contains("label 9 is not in the map") && err.contains("1, 2"),
        "{err}"
    );
    let err = error_of(&["cover", good.to_str().unwrap(), "--segments", "rib"]);
    assert!(err.contains("names no segments"), "{err}");
    let err = error_of(&[
        "cover",
        good.to_str().unwrap(),
        "--labels",
        "2",
        "--max-spheres",
        "1",
        "--tightness",
        "1.5",
    ]);
    assert!(err.contains("needs more than 1 spheres"), "{err}");
    let mut flat = anatomy([0.0; 3]);
    flat.ijk_to_ras[2][2] = 0.0;
    let singular = dir.join("flat.nrrd");
    write_nrrd(&singular, &flat, &style);
    let err = error_of(&["cover", singular.to_str().unwrap()]);
    assert!(
        err.contains("flat.nrrd") && err.contains("singular"),
        "{err}"
    );
    let err = error_of(&["cover", dir.join("missing.nii.gz").to_str().unwrap()]);
    assert!(err.contains("missing.nii.gz"), "{err}");
    let err = error_of(&["cover", dir.join("scan.png").to_str().unwrap()]);
    assert!(err.contains("not a label map or mesh this reads"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// examples/anatomy.toml: the label map's segments become obstacles, the plan keeps clear of
/// every sphere `needle cover` makes of them, and the closed loop reaches the target without a
/// hit (simulated).
#[test]
fn a_scenario_with_anatomy_plans_and_steers() {
    let file = example("anatomy");
    let plan = needle_json(&["plan", file.to_str().unwrap(), "--json"]);
    assert!(plan["best"]["form"].is_string(), "{plan}");
    let map = example("anatomy").with_file_name("anatomy.seg.nrrd");
    let cover = needle_json(&["cover", map.to_str().unwrap(), "--margin", "1", "--json"]);
    let points = plan["best"]["points"].as_array().unwrap();
    for (_, centre, radius) in cover_spheres(&cover) {
        for p in points {
            let p: Vec<f64> = p
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let d = ((p[0] - centre[0]).powi(2)
                + (p[1] - centre[1]).powi(2)
                + (p[2] - centre[2]).powi(2))
            .sqrt();
            assert!(d > radius - 1e-3, "the plan enters a sphere at {p:?}");
        }
    }
    let sim = needle_json(&[
        "simulate",
        file.to_str().unwrap(),
        "--runs",
        "20",
        "--closed-loop",
        "--json",
    ]);
    let s = &sim["summary"];
    assert_eq!(s["collisions"], 0, "{s}");
    let stops: u64 = s["stops"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(stops, 0, "{s}");
}

/// `[[anatomy]]` entries that cannot work: a missing file, a target inside a cover, a plane
/// scenario; each an error naming the entry and the problem.
#[test]
fn bad_anatomy_entries_are_clear_errors() {
    let dir = scratch("entries");
    let map = example("anatomy").with_file_name("anatomy.seg.nrrd");
    let write = |name: &str, target: &str, extra: &str, file: &str| {
        let path = dir.join(name);
        std::fs::write(
            &path,
            format!(
                "[needle]\ncurvature_radius = 63.7\n[entry]\nposition = [8, 32.6, 0]\n\
                 direction = [0, 0, 1]\n[target]\nposition = {target}\n{extra}\n\
                 [[anatomy]]\nfile = {file:?}\n"
            ),
        )
        .unwrap();
        path
    };
    let map_path = map.to_str().unwrap();
    let missing = write("missing.toml", "[8, 32.6, 90]", "", "nowhere.nii.gz");
    let err = error_of(&["plan", missing.to_str().unwrap()]);
    assert!(
        err.contains("anatomy[0]") && err.contains("nowhere.nii.gz"),
        "{err}"
    );
    // The lesion's centre, inside its own cover.
    let inside = write("inside.toml", "[-4, 30.8, 45]", "", map_path);
    let err = error_of(&["plan", inside.to_str().unwrap()]);
    assert!(
        err.contains("the target lies inside the cover of segment \"lesion\""),
        "{err}"
    );
    let plane = write(
        "plane.toml",
        "[8, 32.6, 90]",
        "[planner]\nplane = \"yz\"",
        map_path,
    );
    let err = error_of(&["plan", plane.to_str().unwrap()]);
    assert!(err.contains("anatomy is 3-D"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `[target] label = 1` aims at the lesion's deepest point (the ball's centre), the rib of the
/// same map covered as an obstacle; a label no map holds is an error.
#[test]
fn a_target_given_as_a_label_is_its_deepest_point() {
    let dir = scratch("label");
    let map = example("anatomy").with_file_name("anatomy.seg.nrrd");
    let write = |label: i64| {
        let path = dir.join(format!("label-{label}.toml"));
        std::fs::write(
            &path,
            format!(
                "[needle]\ncurvature_radius = 63.7\n[entry]\nposition = [0, 20, -30]\n\
                 direction = [0, 0, 1]\n[target]\nlabel = {label}\n\
                 [[anatomy]]\nfile = {:?}\nsegments = [\"rib\"]\nmargin_mm = 1.0\n",
                map.to_str().unwrap()
            ),
        )
        .unwrap();
        path
    };
    let plan = needle_json(&["plan", write(1).to_str().unwrap(), "--json"]);
    let points = plan["best"]["points"].as_array().unwrap();
    let end: Vec<f64> = points[points.len() - 1]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let centre = [-4.0, 30.8, 45.0];
    let miss = ((end[0] - centre[0]).powi(2)
        + (end[1] - centre[1]).powi(2)
        + (end[2] - centre[2]).powi(2))
    .sqrt();
    assert!(miss <= 0.1 + 1e-4, "{end:?}");
    let err = error_of(&["plan", write(7).to_str().unwrap()]);
    assert!(
        err.contains("label 7 is in none of") && err.contains("anatomy.seg.nrrd"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A closed box mesh (STL) is covered as the solid it bounds: every corner and a grid of points
/// inside it lie in the cover, in RAS whether the file says RAS or (by default) LPS; the same box
/// as an OBJ (quads, corners repeated) gives the same spheres; open meshes are errors.
#[test]
fn a_closed_mesh_is_covered_as_its_solid() {
    use needle_e2e::label_files::write_stl_box;
    let dir = scratch("mesh");
    let (lo, hi) = ([10.0f32, -4.0, 30.0], [16.0f32, 5.0, 41.0]);
    let ras = dir.join("box-ras.stl");
    let lps = dir.join("box-lps.stl");
    write_stl_box(&ras, lo, hi, "needle-planner test SPACE=RAS", false);
    // The same box as Slicer would save it in LPS (x and y negated).
    write_stl_box(
        &lps,
        [-hi[0], -hi[1], lo[2]],
        [-lo[0], -lo[1], hi[2]],
        "binary STL",
        false,
    );
    for file in [&ras, &lps] {
        let v = needle_json(&["cover", file.to_str().unwrap(), "--voxel", "0.5", "--json"]);
        let s = cover_spheres(&v);
        assert!(!s.is_empty());
        let inside = |p: [f64; 3]| {
            s.iter().any(|(_, c, r)| {
                ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt()
                    <= r + 1e-9
            })
        };
        for a in 0..=6 {
            for b in 0..=6 {
                for c in 0..=6 {
                    let f = |k: usize, n: i32| {
                        f64::from(lo[k]) + f64::from(hi[k] - lo[k]) * f64::from(n) / 6.0
                    };
                    let p = [f(0, a), f(1, b), f(2, c)];
                    assert!(inside(p), "{}: {p:?} outside the cover", file.display());
                }
            }
        }
    }
    // The same box as a Wavefront OBJ of quads, each corner written twice (welded on reading).
    let obj = dir.join("box.obj");
    let mut text = String::from("# SPACE=RAS\n");
    for _ in 0..2 {
        for i in 0..8 {
            let c = [0, 1, 2].map(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] });
            text += &format!("v {} {} {}\n", c[0], c[1], c[2]);
        }
    }
    for (n, q) in [
        [1, 3, 4, 2],
        [5, 6, 8, 7],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 5, 7, 3],
        [2, 4, 8, 6],
    ]
    .iter()
    .enumerate()
    {
        let shift = if n % 2 == 1 { 8 } else { 0 };
        text += &format!(
            "f {} {} {} {}\n",
            q[0] + shift,
            q[1] + shift,
            q[2] + shift,
            q[3] + shift
        );
    }
    std::fs::write(&obj, &text).unwrap();
    let v = needle_json(&["cover", obj.to_str().unwrap(), "--json"]);
    let ras = cover_spheres(&needle_json(&["cover", ras.to_str().unwrap(), "--json"]));
    let from_obj = cover_spheres(&v);
    assert_eq!(from_obj.len(), ras.len());
    for (a, b) in from_obj.iter().zip(&ras) {
        assert!(
            (a.2 - b.2).abs() < 1e-9 && a.1.iter().zip(&b.1).all(|(x, y)| (x - y).abs() < 1e-9)
        );
    }
    let holed = dir.join("holed.obj");
    let cut: String = text
        .lines()
        .filter(|l| !l.starts_with("f 1 3"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&holed, cut).unwrap();
    let err = error_of(&["cover", holed.to_str().unwrap()]);
    assert!(
        err.contains("holed.obj") && err.contains("not closed"),
        "{err}"
    );
    let open = dir.join("open.stl");
    write_stl_box(&open, lo, hi, "SPACE=RAS", true);
    let err = error_of(&["cover", open.to_str().unwrap()]);
    assert!(
        err.contains("open.stl") && err.contains("not closed"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
