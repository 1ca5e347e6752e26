//! Polygon obstacles become circles that cover them entirely, for every method, on convex and
//! concave outlines; scenario files carry polygons inline or in a file.

use needle_e2e::{needle, needle_json, workspace};
use needle_scenario::approx::{approximate, Method};
use needle_scenario::geometry::bounding_box;
use needle_scenario::polygon::Polygon;
use needle_scenario::{load_scenario_shapes, ScenarioFile};

fn shapes() -> Vec<(&'static str, Vec<[f64; 2]>)> {
    let star: Vec<[f64; 2]> = (0..10)
        .map(|k| {
            let a = std::f64::consts::PI * k as f64 / 5.0;
            let r = if k % 2 == 0 { 20.0 } else { 7.0 };
            [5.0 + r * a.cos(), -3.0 + r * a.sin()]
        })
        .collect();
    vec![
        ("triangle", vec![[0.0, 0.0], [30.0, 2.0], [4.0, 11.0]]),
        (
            "hexagon",
            (0..6)
                .map(|k| {
                    let a = k as f64 * 1.047;
                    [10.0 * a.cos(), 6.0 * a.sin()]
                })
                .collect(),
        ),
        (
            "long bar",
            vec![[0.0, 0.0], [80.0, 5.0], [79.0, 12.0], [-1.0, 7.0]],
        ),
        (
            "L",
            vec![
                [0.0, 0.0],
                [40.0, 0.0],
                [40.0, 5.0],
                [5.0, 5.0],
                [5.0, 30.0],
                [0.0, 30.0],
            ],
        ),
        (
            "U",
            vec![
                [0.0, 0.0],
                [20.0, 0.0],
                [20.0, 18.0],
                [16.0, 18.0],
                [16.0, 4.0],
                [4.0, 4.0],
                [4.0, 18.0],
                [0.0, 18.0],
            ],
        ),
        ("star", star),
        (
            "comb",
            vec![
                [0.0, 0.0],
                [30.0, 0.0],
                [30.0, 20.0],
                [26.0, 20.0],
                [26.0, 3.0],
                [17.0, 3.0],
                [17.0, 20.0],
                [13.0, 20.0],
                [13.0, 3.0],
                [4.0, 3.0],
                [4.0, 20.0],
                [0.0, 20.0],
            ],
        ),
    ]
}

/// Grid points inside the polygon at `step` spacing, plus points along its outline.
fn dense_samples(p: &Polygon, step: f64) -> Vec<[f64; 2]> {
    let v = p.vertices();
    let (lo, hi) = bounding_box(v);
    let mut out = Vec::new();
    let mut y = lo[0];
    while y <= hi[0] {
        let mut z = lo[1];
        while z <= hi[1] {
            if p.contains([y, z]) {
                out.push([y, z]);
            }
            z += step;
        }
        y += step;
    }
    for i in 0..v.len() {
        let (a, b) = (v[i], v[(i + 1) % v.len()]);
        for k in 0..=200 {
            let t = k as f64 / 200.0;
            out.push([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]);
        }
    }
    out
}

#[test]
fn every_method_covers_convex_and_concave_polygons() {
    for (name, outline) in shapes() {
        let poly = Polygon::new(outline).unwrap();
        let samples = dense_samples(&poly, 0.1);
        assert!(samples.len() > 1000, "{name}: {} samples", samples.len());
        for method in Method::ALL {
            let a = approximate(&poly, method);
            assert!(!a.circles.is_empty(), "{name} {method}");
            for s in &samples {
                assert!(
                    a.circles.iter().any(|c| c.contains(*s, 0.0)),
                    "{name} {method}: sample {s:?} outside every circle {:?}",
                    a.circles
                );
            }
            // The union covers the polygon, so it is no smaller; what it adds is reported.
            assert!(
                a.covered_area >= a.polygon_area * (1.0 - 1e-9),
                "{name} {method}"
            );
            assert!((a.added_area() - (a.covered_area - a.polygon_area)).abs() < 1e-9);
        }
    }
}

#[test]
fn finer_methods_add_less_area_on_thin_concave_shapes() {
    for (name, outline) in shapes()
        .into_iter()
        .filter(|(n, _)| ["L", "U", "comb"].contains(n))
    {
        let poly = Polygon::new(outline).unwrap();
        let one = approximate(&poly, Method::Circumscribed);
        let seg = approximate(&poly, Method::Segmented);
        let bord = approximate(&poly, Method::Bordered);
        assert_eq!(one.circles.len(), 1);
        assert!(seg.added_area() < one.added_area(), "{name}");
        assert!(bord.added_area() < one.added_area(), "{name}");
        assert!(bord.circles.len() > seg.circles.len(), "{name}");
    }
}

#[test]
fn scenario_file_polygons_become_covering_planner_circles() {
    let file = workspace().join("tests/data/polygons.toml");
    for method in [
        None,
        Some(Method::Circumscribed),
        Some(Method::Segmented),
        Some(Method::Bordered),
    ] {
        let shapes = ScenarioFile::load(&file)
            .unwrap()
            .obstacle_shapes(method)
            .unwrap();
        assert_eq!(shapes.len(), 3);
        let count: usize = shapes.iter().map(|s| s.circles.len()).sum();
        match load_scenario_shapes(&file, method) {
            Ok((scenario, _)) => assert_eq!(scenario.obstacles.len(), count),
            Err(e) => {
                // Bordering all three needs more circles than the planner holds: a clear error.
                assert!(count > planner_core::MAX_OBSTACLES, "{e:#}");
                assert!(format!("{e:#}").contains("coarser approximation"), "{e:#}");
            }
        }
        for s in &shapes {
            let (poly, a) = s.polygon.as_ref().expect("all three are polygons");
            if let Some(m) = method {
                assert_eq!(a.method, m);
            }
            // The planner's f32 circles still cover a dense sampling of the polygon.
            for q in dense_samples(poly, 0.25) {
                let covered = s.circles.iter().any(|c| {
                    let (dy, dz) = (f64::from(c.center[1]) - q[0], f64::from(c.center[2]) - q[1]);
                    dy.hypot(dz) <= f64::from(c.radius)
                });
                assert!(covered, "obstacle {} sample {q:?}", s.index);
            }
        }
        // Each obstacle's own `approx` applies when no override is given.
        if method.is_none() {
            let methods: Vec<Method> = shapes
                .iter()
                .map(|s| s.polygon.as_ref().unwrap().1.method)
                .collect();
            assert_eq!(
                methods,
                vec![Method::Circumscribed, Method::Segmented, Method::Bordered]
            );
        }
    }
}

#[test]
fn bad_polygon_obstacles_are_clear_errors() {
    let base = std::fs::read_to_string(workspace().join("examples/paper.toml")).unwrap();
    let with = |extra: &str| {
        let f = ScenarioFile::parse(&format!("{base}\n{extra}")).unwrap();
        format!("{:#}", f.to_scenario().unwrap_err())
    };
    let crossing = with("[[obstacles]]\npolygon = [[0, 60], [10, 70], [10, 60], [0, 70]]");
    assert!(crossing.contains("crosses itself"), "{crossing}");
    let target = with("[[obstacles]]\npolygon = [[-5, 85], [5, 85], [5, 95], [-5, 95]]");
    assert!(
        target.contains("target lies inside the polygon"),
        "{target}"
    );
    let both = with(
        "[[obstacles]]\ncenter = [0, 1, 70]\nradius = 2\npolygon = [[0, 60], [10, 70], [10, 60]]",
    );
    assert!(both.contains("no center or radius"), "{both}");
    let method =
        with("[[obstacles]]\npolygon = [[20, 60], [30, 70], [30, 60]]\napprox = \"round\"");
    assert!(
        method.contains("circumscribed, segmented or bordered"),
        "{method}"
    );
    // Polygons live in the y-z plane: 3-D scenarios must say so.
    let space = base.replace("plane = \"yz\"", "");
    let f = ScenarioFile::parse(&format!(
        "{space}\n[[obstacles]]\npolygon = [[20, 60], [30, 70], [30, 60]]"
    ))
    .unwrap();
    let err = format!("{:#}", f.to_scenario().unwrap_err());
    assert!(err.contains("planner.plane"), "{err}");
}

#[test]
fn approx_command_reports_circles_and_added_area() {
    let v = needle_json(&[
        "approx",
        "tests/data/polygons.toml",
        "--method",
        "segmented",
        "--json",
    ]);
    let obs = v["obstacles"].as_array().unwrap();
    assert_eq!(obs.len(), 3);
    for o in obs {
        assert_eq!(o["method"], "segmented");
        let added = o["added_area"].as_f64().unwrap();
        let (cov, area) = (
            o["covered_area"].as_f64().unwrap(),
            o["polygon_area"].as_f64().unwrap(),
        );
        assert!(added > 0.0 && (cov - area - added).abs() < 1e-6);
        assert!(!o["circles"].as_array().unwrap().is_empty());
    }
    let bad = needle()
        .args(["approx", "tests/data/polygons.toml", "--method", "hull"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
}
