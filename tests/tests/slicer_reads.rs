//! 3D Slicer's own readers on the files needle exports, and Slicer's writer on a file needle reads:
//! slicer-core (Slicer's MRML library for Python, from PyPI; `tests/python/slicer_files.py` in
//! the venv `scripts/python-env` makes) loads the plan's curve, the entry and target, the
//! obstacles' model and the simulated paths, and sees them where needle put them (RAS); a point
//! Slicer saves (LPS, its default) is planned to where Slicer placed it.

use needle_e2e::{example, needle_json, venv_script};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn scratch(test: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("needle-slicer-reads-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `tests/python/slicer_files.py` with `args`; its JSON on stdout.
fn slicer(args: &[&str]) -> String {
    String::from_utf8(venv_script("slicer_files.py", args)).unwrap()
}

/// What Slicer loaded from each file, by file name.
fn slicer_reads(dir: &Path, files: &[&str]) -> Vec<Value> {
    let paths: Vec<String> = files
        .iter()
        .map(|f| dir.join(f).to_str().unwrap().to_string())
        .collect();
    let mut args = vec!["read"];
    args.extend(paths.iter().map(String::as_str));
    let out: Vec<Value> = serde_json::from_str(slicer(&args).trim()).unwrap();
    for v in &out {
        assert_eq!(v["loaded"], true, "Slicer could not load {}", v["file"]);
    }
    out
}

fn triples(v: &Value) -> Vec<[f64; 3]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let p = p.as_array().unwrap();
            [0, 1, 2].map(|i| p[i].as_f64().unwrap())
        })
        .collect()
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// The bounds (xmin, xmax, ymin, ymax, zmin, zmax) of a legacy VTK file's points, turned to RAS
/// as its `SPACE=LPS` header says, read here without Slicer.
fn ras_bounds_of_vtk(path: &Path) -> [f64; 6] {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.lines().nth(1).unwrap().ends_with("SPACE=LPS"));
    let mut b = [f64::MAX, f64::MIN, f64::MAX, f64::MIN, f64::MAX, f64::MIN];
    let rows = text
        .lines()
        .skip_while(|l| !l.starts_with("POINTS"))
        .skip(1)
        .take_while(|l| l.starts_with(|c: char| c == '-' || c.is_ascii_digit()));
    for row in rows {
        let v: Vec<f64> = row.split_whitespace().map(|x| x.parse().unwrap()).collect();
        for (axis, x) in [-v[0], -v[1], v[2]].into_iter().enumerate() {
            b[2 * axis] = b[2 * axis].min(x);
            b[2 * axis + 1] = b[2 * axis + 1].max(x);
        }
    }
    b
}

/// Slicer loads the curve as a curve with needle's points, the entry and target as a labelled
/// point list at the scenario's points, and both models with their vertices where needle's LPS
/// files put them once turned to RAS: one polyline per simulated run.
#[test]
fn slicer_loads_what_needle_exports() {
    let dir = scratch("export");
    let file = example("anatomy");
    let runs = 3;
    needle_json(&[
        "simulate",
        file.to_str().unwrap(),
        "--runs",
        &runs.to_string(),
        "--closed-loop",
        "--json",
        "--export",
        dir.to_str().unwrap(),
    ]);
    let files = [
        "plan.mrk.json",
        "entry-target.mrk.json",
        "obstacles.vtk",
        "paths-closed-loop.vtk",
    ];
    let seen = slicer_reads(&dir, &files);

    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join(files[0])).unwrap()).unwrap();
    let ours: Vec<Value> = written["markups"][0]["controlPoints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["position"].clone())
        .collect();
    let ours = triples(&Value::Array(ours));
    assert_eq!(seen[0]["class"], "vtkMRMLMarkupsCurveNode");
    let curve = triples(&seen[0]["points"]);
    assert_eq!(curve.len(), ours.len());
    assert!(curve.iter().zip(&ours).all(|(a, b)| close(*a, *b, 1e-4)));

    assert_eq!(seen[1]["class"], "vtkMRMLMarkupsFiducialNode");
    assert_eq!(seen[1]["labels"], serde_json::json!(["entry", "target"]));
    let ends = triples(&seen[1]["points"]);
    assert!(close(ends[0], [8.0, 32.6, 0.0], 1e-4), "{ends:?}");
    assert!(close(ends[1], [8.0, 32.6, 90.0], 1e-4), "{ends:?}");
    assert!(close(curve[0], ends[0], 1e-4));

    for (k, model) in seen[2..].iter().enumerate() {
        let want = ras_bounds_of_vtk(&dir.join(files[2 + k]));
        let got: Vec<f64> = model["bounds"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-3, "{}: {got:?} {want:?}", files[2 + k]);
        }
    }
    assert_eq!(seen[3]["cells"], runs);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A target Slicer saves (a point list in LPS, the coordinate system Slicer writes by default,
/// under its newer schema) plans exactly as the same point typed into the scenario.
#[test]
fn a_point_slicer_saves_is_planned_where_slicer_placed_it() {
    let dir = scratch("write");
    let target = dir.join("target.mrk.json");
    slicer(&["write", target.to_str().unwrap(), "lesion", "12", "8", "85"]);
    let saved: Value = serde_json::from_str(&std::fs::read_to_string(&target).unwrap()).unwrap();
    assert_eq!(saved["markups"][0]["coordinateSystem"], "LPS");
    let text = std::fs::read_to_string(example("space")).unwrap();
    assert!(text.contains("position = [12.0, 8.0, 85.0]"));
    let from_slicer = text.replace(
        "position = [12.0, 8.0, 85.0]",
        "markups = \"target.mrk.json\"",
    );
    let scenario = dir.join("space-slicer.toml");
    std::fs::write(&scenario, from_slicer).unwrap();
    let typed = needle_json(&["plan", example("space").to_str().unwrap(), "--json"]);
    let read_in = needle_json(&["plan", scenario.to_str().unwrap(), "--json"]);
    assert_eq!(read_in["best"]["form"], typed["best"]["form"]);
    assert_eq!(read_in["best"]["length"], typed["best"]["length"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A segmentation Slicer saves (`.seg.nrrd`: LPS, gzip, segments cropped to their extent with
/// names, label values and layers in the header) is covered where Slicer put it: the lesion, a
/// voxel ball of radius 6, by one sphere on its centre at most half a voxel's diagonal larger;
/// every corner of every voxel of the rib, a box, inside the rib's spheres (checked exhaustively).
#[test]
fn a_segmentation_slicer_saves_is_covered_where_slicer_put_it() {
    let dir = scratch("segmentation");
    let file = dir.join("anatomy.seg.nrrd");
    slicer(&["segmentation", file.to_str().unwrap()]);
    let report = needle_json(&[
        "cover",
        file.to_str().unwrap(),
        "--segments",
        "lesion,rib",
        "--json",
    ]);
    let segment = |name: &str| {
        report["segments"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["name"] == name)
            .unwrap_or_else(|| panic!("no segment {name} in {report}"))
            .clone()
    };
    let spheres = |s: &Value| -> Vec<([f64; 3], f64)> {
        s["spheres"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| {
                (
                    triples(&Value::Array(vec![b["center"].clone()]))[0],
                    b["radius"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    // Voxel (i, j, k) of the script's grid is at RAS (-15 + i, 5 + j, 20 + k).
    let at =
        |i: i32, j: i32, k: i32| [f64::from(i) - 15.0, f64::from(j) + 5.0, f64::from(k) + 20.0];
    let lesion = segment("lesion");
    assert_eq!(lesion["voxels"], 925);
    let ball = spheres(&lesion);
    assert_eq!(ball.len(), 1, "{lesion}");
    assert!(close(ball[0].0, at(10, 12, 14), 1e-4), "{lesion}");
    assert!(
        ball[0].1 >= 6.0 && ball[0].1 <= 6.0 + 3f64.sqrt() / 2.0 + 1e-9,
        "{lesion}"
    );

    let rib = segment("rib");
    assert_eq!(rib["voxels"], 6 * 20 * 9);
    let cover = spheres(&rib);
    for i in 20..26 {
        for j in 5..25 {
            for k in 3..12 {
                let c = at(i, j, k);
                for corner in 0..8 {
                    let p = [0, 1, 2].map(|a| c[a] + if corner >> a & 1 == 1 { 0.5 } else { -0.5 });
                    let inside = cover.iter().any(|(o, r)| {
                        let d2: f64 = (0..3).map(|a| (p[a] - o[a]).powi(2)).sum();
                        d2.sqrt() <= r + 1e-6
                    });
                    assert!(
                        inside,
                        "rib voxel ({i}, {j}, {k}) corner {p:?} outside {cover:?}"
                    );
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
