//! The files 3D Slicer exchanges with a plan: `needle plan --export DIR` (markups in RAS, the
//! obstacles as a model in LPS) and `[entry]` / `[target]` read from markups (`.mrk.json`, LPS
//! or RAS): written, read back, and the same plan whichever way the points arrive.

use needle_e2e::{example, needle, needle_json};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-slicer-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn read(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn positions(markups: &Value) -> Vec<[f64; 3]> {
    markups["markups"][0]["controlPoints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let v: Vec<f64> = p["position"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The markups hold what Slicer's schema asks of them (the `@schema` URL, a markups array, a
/// type and a coordinate system from its enumerations, positions of three numbers), the curve
/// runs from the entry to the target with points at most 1 mm apart, and the model's vertices
/// lie on the obstacles' spheres, in LPS.
#[test]
fn plan_export_writes_markups_and_a_model() {
    let dir = scratch("export");
    let file = example("space");
    let plan = needle_json(&[
        "plan",
        file.to_str().unwrap(),
        "--json",
        "--export",
        dir.to_str().unwrap(),
    ]);
    let curve = read(&dir.join("plan.mrk.json"));
    let points = read(&dir.join("entry-target.mrk.json"));
    for m in [&curve, &points] {
        assert!(m["@schema"]
            .as_str()
            .unwrap()
            .ends_with("markups-schema-v1.0.3.json#"));
        let markup = &m["markups"][0];
        assert!(["Fiducial", "Curve"].contains(&markup["type"].as_str().unwrap()));
        assert_eq!(markup["coordinateSystem"], "RAS");
        assert_eq!(markup["coordinateUnits"], "mm");
    }
    assert_eq!(curve["markups"][0]["type"], "Curve");
    let path = positions(&curve);
    let ends = positions(&points);
    assert_eq!(points["markups"][0]["controlPoints"][1]["label"], "target");
    assert!(dist(path[0], ends[0]) < 1e-4);
    assert!(dist(path[path.len() - 1], ends[1]) <= 0.1 + 1e-4);
    assert!(path.windows(2).all(|w| dist(w[0], w[1]) <= 1.0 + 1e-4));
    let length: f64 = path.windows(2).map(|w| dist(w[0], w[1])).sum();
    assert!(
        (length - plan["best"]["length"].as_f64().unwrap()).abs() < 0.05,
        "{length}"
    );
    // The model: 2 + 9 * 20 vertices per sphere, each on its sphere once turned back to RAS.
    let vtk = std::fs::read_to_string(dir.join("obstacles.vtk")).unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    let spheres: Vec<([f64; 3], f64)> = text
        .split("[[obstacles]]")
        .skip(1)
        .map(|block| {
            let nums = |key: &str| -> Vec<f64> {
                let line = block
                    .lines()
                    .find(|l| l.trim_start().starts_with(key))
                    .unwrap();
                line.split('=')
                    .nth(1)
                    .unwrap()
                    .trim()
                    .trim_matches(|c| c == '[' || c == ']')
                    .split(',')
                    .map(|x| x.trim().parse().unwrap())
                    .collect()
            };
            let c = nums("center");
            ([c[0], c[1], c[2]], nums("radius")[0])
        })
        .collect();
    let verts: Vec<[f64; 3]> = vtk
        .lines()
        .skip_while(|l| !l.starts_with("POINTS"))
        .skip(1)
        .take_while(|l| !l.starts_with("POLYGONS"))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [-v[0], -v[1], v[2]]
        })
        .collect();
    assert_eq!(verts.len(), spheres.len() * (2 + 9 * 20));
    for (k, v) in verts.iter().enumerate() {
        let (c, r) = spheres[k / (2 + 9 * 20)];
        assert!((dist(*v, c) - r).abs() < 1e-3, "vertex {k}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Entry and target read from markups (one file in LPS as Slicer saves it, one the export wrote,
/// in RAS, by label) plan exactly as the same points typed in.
#[test]
fn entry_and_target_from_markups_plan_as_typed() {
    let dir = scratch("read");
    let typed = needle_json(&[
        "plan",
        example("space").to_str().unwrap(),
        "--json",
        "--export",
        dir.to_str().unwrap(),
    ]);
    let ends = positions(&read(&dir.join("entry-target.mrk.json")));
    let lps = serde_json::json!({
        "@schema": "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/markups-schema-v1.0.3.json#",
        "markups": [{"type": "Fiducial", "coordinateSystem": "LPS", "controlPoints": [
            {"id": "1", "label": "skin", "position": [-ends[0][0], -ends[0][1], ends[0][2]]}
        ]}]
    });
    std::fs::write(dir.join("entry.mrk.json"), lps.to_string()).unwrap();
    let text = std::fs::read_to_string(example("space")).unwrap();
    let mut out = String::new();
    let mut table = "";
    for line in text.lines() {
        if line.starts_with('[') {
            table = line.trim();
        }
        if line.starts_with("position") && table == "[entry]" {
            out += "markups = \"entry.mrk.json\"\n";
        } else if line.starts_with("position") && table == "[target]" {
            out += "markups = \"entry-target.mrk.json\"\npoint = \"target\"\n";
        } else {
            out += line;
            out += "\n";
        }
    }
    let scenario = dir.join("from-markups.toml");
    std::fs::write(&scenario, out).unwrap();
    let read_in = needle_json(&["plan", scenario.to_str().unwrap(), "--json"]);
    assert_eq!(read_in["best"]["form"], typed["best"]["form"]);
    assert_eq!(read_in["best"]["length"], typed["best"]["length"]);
    // A label the file does not hold: the labels it does hold are named.
    let bad = std::fs::read_to_string(&scenario)
        .unwrap()
        .replace("point = \"target\"", "point = \"lesion\"");
    std::fs::write(&scenario, bad).unwrap();
    let run = needle()
        .args(["plan", scenario.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        err.contains("no control point labelled \"lesion\"")
            && err.contains("\"entry\", \"target\""),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `needle simulate --export DIR`: the plan's files, and every simulated path as one polyline of
/// a model (LPS), the same points the run reports in `--detail`.
#[test]
fn simulate_export_writes_every_path() {
    let dir = scratch("simulate");
    let file = example("paper");
    let v = needle_json(&[
        "simulate",
        file.to_str().unwrap(),
        "--runs",
        "6",
        "--closed-loop",
        "--json",
        "--detail",
        "--export",
        dir.to_str().unwrap(),
    ]);
    assert!(dir.join("plan.mrk.json").exists() && dir.join("entry-target.mrk.json").exists());
    let vtk = std::fs::read_to_string(dir.join("paths-closed-loop.vtk")).unwrap();
    let verts: Vec<[f64; 3]> = vtk
        .lines()
        .skip_while(|l| !l.starts_with("POINTS"))
        .skip(1)
        .take_while(|l| !l.starts_with("LINES"))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [-v[0], -v[1], v[2]]
        })
        .collect();
    let lines: Vec<Vec<usize>> = vtk
        .lines()
        .skip_while(|l| !l.starts_with("LINES"))
        .skip(1)
        .map(|l| {
            l.split_whitespace()
                .skip(1)
                .map(|x| x.parse().unwrap())
                .collect()
        })
        .collect();
    let runs = v["runs_detail"].as_array().unwrap();
    assert_eq!(lines.len(), runs.len());
    for (line, run) in lines.iter().zip(runs) {
        let points = run["points"].as_array().unwrap();
        assert_eq!(line.len(), points.len());
        for (&k, p) in line.iter().zip(points) {
            let p: Vec<f64> = p
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            assert!(
                dist(verts[k], [p[0], p[1], p[2]]) < 1e-5,
                "{:?} {p:?}",
                verts[k]
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `needle plan --export DIR` says on stderr which files it wrote (it said nothing), and leaves
/// stdout the report.
#[test]
fn export_says_what_it_wrote() {
    let dir = scratch("export-says");
    let file = example("anatomy");
    let out = needle()
        .args([
            "plan",
            file.to_str().unwrap(),
            "--export",
            dir.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    for name in ["plan.mrk.json", "entry-target.mrk.json", "obstacles.vtk"] {
        let path = dir.join(name);
        assert!(path.exists(), "{name}");
        assert!(err.contains(&path.display().to_string()), "{name}: {err}");
    }
    assert!(!String::from_utf8_lossy(&out.stdout).contains("wrote"));
    let _ = std::fs::remove_dir_all(&dir);
}
