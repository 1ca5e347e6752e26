//! `needle plot` of a scenario with `[[anatomy]]`: slices of the label map through a point, read
//! back from the SVG's coordinates. A ball (label 1, covered) and a box (label 2, not covered)
//! written here as NRRD: the ball's slice lies where the ball is, the covering sphere's section
//! is the sphere's circle, the best path runs from the entry; bad slice points are clear errors.

use needle_e2e::label_files::{cover_spheres, write_nrrd, Labels, NrrdStyle};
use needle_e2e::{needle, needle_json};
use std::path::{Path, PathBuf};

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-slices-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The ball: radius 8 mm about (0, 0, 45) RAS, on 0.8 x 1 x 1.25 mm voxels; the box: label 2.
const CENTRE: [f64; 3] = [0.0, 0.0, 45.0];
const RADIUS: f64 = 8.0;
const SPACING: [f64; 3] = [0.8, 1.0, 1.25];

/// Writes the map (in LPS, as Slicer does) and a scenario that covers label 1 only.
fn write_case(dir: &Path) -> PathBuf {
    let a = [
        [SPACING[0], 0.0, 0.0, -20.0],
        [0.0, SPACING[1], 0.0, -20.0],
        [0.0, 0.0, SPACING[2], 20.0],
    ];
    let m = Labels::of([50, 40, 40], a, |i, j, k| {
        let w = [
            -20.0 + i as f64 * SPACING[0],
            -20.0 + j as f64 * SPACING[1],
            20.0 + k as f64 * SPACING[2],
        ];
        let d: f64 = (0..3).map(|n| (w[n] - CENTRE[n]).powi(2)).sum();
        if d.sqrt() <= RADIUS {
            1
        } else if (2..6).contains(&i) && (2..6).contains(&j) && (15..25).contains(&k) {
            2
        } else {
            0
        }
    });
    let style = NrrdStyle {
        space: "left-posterior-superior",
        gzip: true,
        pairs: &[],
    };
    write_nrrd(&dir.join("ball.nrrd"), &m, &style);
    // As tight as `needle cover` makes it by default: one sphere, the one the test draws.
    let scenario = dir.join("ball.toml");
    std::fs::write(
        &scenario,
        "[needle]\ncurvature_radius = 63.7\n[entry]\nposition = [0, 15, 0]\n\
         direction = [0, 0, 1]\n[target]\nposition = [0, 15, 90]\n\
         [[anatomy]]\nfile = \"ball.nrrd\"\nlabels = [1]\ntightness = 1.5\n",
    )
    .unwrap();
    scenario
}

/// The value of attribute `name` in element text `e`.
fn attr<'a>(e: &'a str, name: &str) -> &'a str {
    let key = format!(" {name}=\"");
    let start = e.find(&key).unwrap_or_else(|| panic!("no {name} in {e}")) + key.len();
    &e[start..start + e[start..].find('"').unwrap()]
}

fn num(e: &str, name: &str) -> f64 {
    attr(e, name).parse().unwrap()
}

/// One panel: its fixed axis, the world-to-pixel map (A, B, S) and its elements.
struct Panel<'a> {
    axes: [usize; 2],
    px: [f64; 3],
    body: &'a str,
}

impl Panel<'_> {
    /// The world point (h, v) of pixel (x, y).
    fn world(&self, x: f64, y: f64) -> [f64; 2] {
        let [a, b, s] = self.px;
        [(x - a) / s, (b - y) / s]
    }

    fn elements(&self, start: &str) -> Vec<&str> {
        self.body
            .split('<')
            .filter(|e| e.starts_with(start))
            .collect()
    }
}

fn panels(svg: &str) -> Vec<Panel<'_>> {
    let axis = |c: char| "xyz".find(c).unwrap();
    svg.split(r#"<g class="slice""#)
        .skip(1)
        .map(|body| {
            let head = &body[..body.find('>').unwrap()];
            let axes: Vec<usize> = attr(head, "data-axes").chars().map(axis).collect();
            let px: Vec<f64> = attr(head, "data-px")
                .split(' ')
                .map(|v| v.parse().unwrap())
                .collect();
            Panel {
                axes: [axes[0], axes[1]],
                px: [px[0], px[1], px[2]],
                body,
            }
        })
        .collect()
}

#[test]
fn the_slices_show_the_ball_its_sphere_and_the_path() {
    let dir = scratch("ball");
    let scenario = write_case(&dir);
    let out = dir.join("ball.svg");
    let run = needle()
        .args([
            "plot",
            scenario.to_str().unwrap(),
            "--slice-at",
            "0,0,45",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let svg = std::fs::read_to_string(&out).unwrap();
    let cover = needle_json(&[
        "cover",
        dir.join("ball.nrrd").to_str().unwrap(),
        "--labels",
        "1",
        "--json",
    ]);
    let spheres = cover_spheres(&cover);
    assert_eq!(spheres.len(), 1, "{spheres:?}");
    let plan = needle_json(&["plan", scenario.to_str().unwrap(), "--json"]);
    let points: Vec<Vec<f64>> = serde_json::from_value(plan["best"]["points"].clone()).unwrap();
    let panels = panels(&svg);
    assert_eq!(panels.len(), 3);
    for p in &panels {
        let [h, v] = p.axes;
        // The ball's cells: inside its circle on this plane (through its centre), reaching out
        // to its radius within a voxel and a sampling cell.
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let chosen = p.elements(r#"rect class="label chosen""#);
        assert!(!chosen.is_empty());
        for r in &chosen {
            assert_eq!(attr(r, "data-label"), "1");
            let (x, y, w, ht) = (num(r, "x"), num(r, "y"), num(r, "width"), num(r, "height"));
            let a = p.world(x, y + ht);
            let b = p.world(x + w, y);
            for k in 0..2 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
            }
            let mid = p.world(x + w / 2.0, y + ht / 2.0);
            let off = ((mid[0] - CENTRE[h]).powi(2) + (mid[1] - CENTRE[v]).powi(2)).sqrt();
            assert!(
                off <= RADIUS + 1.0,
                "a ball cell {off} mm from its centre: {r}"
            );
        }
        for (k, axis) in [h, v].into_iter().enumerate() {
            let slack = SPACING[axis] + 0.01;
            assert!(
                (lo[k] - (CENTRE[axis] - RADIUS)).abs() <= slack,
                "{lo:?} along {axis}"
            );
            assert!(
                (hi[k] - (CENTRE[axis] + RADIUS)).abs() <= slack,
                "{hi:?} along {axis}"
            );
        }
        // The box (label 2) is cut by the axial plane only, drawn faint, not as chosen.
        let others = p.elements(r#"rect class="label" data-map="0" data-label="2""#);
        assert_eq!(!others.is_empty(), p.axes == [0, 1], "{:?}", p.axes);
        // The cover's one sphere, cut through its centre: its own circle.
        let circles = p.elements(r#"circle class="sphere-section""#);
        assert_eq!(circles.len(), 1);
        let c = p.world(num(circles[0], "cx"), num(circles[0], "cy"));
        let (centre, radius) = (spheres[0].1, spheres[0].2);
        assert!(
            (c[0] - centre[h]).abs() < 0.01 && (c[1] - centre[v]).abs() < 0.01,
            "{c:?}"
        );
        assert!((num(circles[0], "r") / p.px[2] - radius).abs() < 0.01);
        // The best path, projected: from the entry to the plan's last point.
        let best = p.elements(r#"polyline class="path best""#);
        assert_eq!(best.len(), 1);
        let pts: Vec<[f64; 2]> = attr(best[0], "points")
            .split(' ')
            .map(|xy| {
                let (x, y) = xy.split_once(',').unwrap();
                p.world(x.parse().unwrap(), y.parse().unwrap())
            })
            .collect();
        let last = &points[points.len() - 1];
        for (got, want) in [
            (pts[0], [0.0, 15.0, 0.0]),
            (pts[pts.len() - 1], [last[0], last[1], last[2]]),
        ] {
            assert!(
                (got[0] - want[h]).abs() < 0.05 && (got[1] - want[v]).abs() < 0.05,
                "{got:?}"
            );
        }
    }
    assert!(svg.contains(">label 1, covered<"));
    let _ = std::fs::remove_dir_all(&dir);
}

fn error_of(args: &[&str]) -> String {
    let out = needle().args(args).output().unwrap();
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// The default slice point (the path's closest approach, moved into the map) draws three
/// panels; a typed point outside the map, a malformed one, and a scenario without anatomy are
/// errors that say so.
#[test]
fn bad_slice_points_are_clear_errors() {
    let dir = scratch("bad");
    let scenario = write_case(&dir);
    let s = scenario.to_str().unwrap();
    let out = dir.join("default.svg");
    let o = out.to_str().unwrap();
    let run = needle().args(["plot", s, "-o", o]).output().unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(panels(&std::fs::read_to_string(&out).unwrap()).len(), 3);
    let err = error_of(&["plot", s, "--slice-at", "0,0,200", "-o", o]);
    assert!(
        err.contains("(0.00, 0.00, 200.00)")
            && err.contains("outside every label map")
            && err.contains("ball.nrrd: x -20.4..19.6"),
        "{err}"
    );
    let err = error_of(&["plot", s, "--slice-at", "1,2", "-o", o]);
    assert!(err.contains("X,Y,Z"), "{err}");
    let err = error_of(&["plot", s, "--slice-at", "nan,0,0", "-o", o]);
    assert!(err.contains("finite"), "{err}");
    let err = error_of(&[
        "plot",
        "examples/space.toml",
        "--slice-at",
        "0,0,0",
        "-o",
        o,
    ]);
    assert!(err.contains("has no [[anatomy]]"), "{err}");
    // `--projections` keeps the plot of a scenario without anatomy: no slices.
    let run = needle()
        .args(["plot", s, "--projections", "-o", o])
        .output()
        .unwrap();
    assert!(run.status.success());
    assert!(panels(&std::fs::read_to_string(&out).unwrap()).is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The points of a polyline element, as pixels.
fn polyline_points(e: &str) -> Vec<[f64; 2]> {
    attr(e, "points")
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            [x.parse().unwrap(), y.parse().unwrap()]
        })
        .collect()
}

/// Runs `needle ARGS --plot OUT` and returns the SVG it wrote.
fn drawn(args: &[&str], out: &Path) -> String {
    let run = needle()
        .args(args)
        .args(["--plot", out.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    std::fs::read_to_string(out).unwrap()
}

/// `needle plan --plot` and `needle simulate --plot` of a scenario with anatomy draw the slices
/// too: the planned path in each panel, and for the simulation every run's path, which starts
/// at the entry (0, 15, 0) and ends within a few millimetres of the target (0, 15, 90) in world
/// coordinates read back from the panels.
#[test]
fn plan_and_simulate_plots_slice_the_anatomy() {
    let dir = scratch("plots");
    let scenario = write_case(&dir);
    let s = scenario.to_str().unwrap();
    let text = drawn(&["plan", s], &dir.join("plan.svg"));
    let planned = panels(&text);
    assert_eq!(planned.len(), 3);
    assert!(planned
        .iter()
        .all(|p| !p.elements("polyline class=\"path best\"").is_empty()));
    let args = ["simulate", s, "--closed-loop", "--runs", "6"];
    let text = drawn(&args, &dir.join("simulate.svg"));
    let panels = panels(&text);
    assert_eq!(panels.len(), 3);
    for p in &panels {
        let runs = p.elements("polyline class=\"executed\"");
        assert_eq!(runs.len(), 6, "every run in the {:?} panel", p.axes);
        let world = |axis: usize| [0.0, 15.0, 90.0][axis];
        for r in runs {
            let pts = polyline_points(r);
            let first = pts[0];
            let last = pts[pts.len() - 1];
            let start = p.world(first[0], first[1]);
            let end = p.world(last[0], last[1]);
            for (k, &axis) in p.axes.iter().enumerate() {
                let entry = [0.0, 15.0, 0.0][axis];
                assert!(
                    (start[k] - entry).abs() < 2.0,
                    "start {start:?} in {:?}",
                    p.axes
                );
                assert!(
                    (end[k] - world(axis)).abs() < 2.0,
                    "end {end:?} in {:?}",
                    p.axes
                );
            }
        }
    }
    assert!(text.contains("closed loop, not stopped"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `needle plot examples/anatomy.toml` draws the plan `needle plan` prints: planned itself, its
/// SVG is the one drawn from `needle plan --json`'s file (it planned without the collision
/// bound's rounds, and drew another best path).
#[test]
fn plot_draws_the_plan_that_plan_prints() {
    let dir = std::env::temp_dir().join(format!("needle-plot-plan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = needle_e2e::example("anatomy");
    let file = file.to_str().unwrap();
    let plan = needle_e2e::needle_stdout(&["plan", file, "--json"]);
    let plan_path = dir.join("plan.json");
    std::fs::write(&plan_path, plan).unwrap();
    let (own, from_file) = (dir.join("own.svg"), dir.join("file.svg"));
    needle_e2e::needle_stdout(&["plot", file, "-o", own.to_str().unwrap()]);
    let args = ["plot", file, "--plan", plan_path.to_str().unwrap(), "-o"];
    let mut args = args.to_vec();
    args.push(from_file.to_str().unwrap());
    needle_e2e::needle_stdout(&args);
    let (a, b) = (
        std::fs::read(&own).unwrap(),
        std::fs::read(&from_file).unwrap(),
    );
    assert!(a == b, "the plot drew another plan than needle plan");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The best path's stretches within 2 mm of a slice's plane are marked on it, and only those: on
/// `examples/anatomy.toml`, every marked point is a point of the plan within 2 mm of the plane
/// and every such point is marked; a plane 20 mm from the path marks nothing (its projection
/// alone seemed to cross the organs).
#[test]
fn the_slices_mark_where_the_path_is_in_the_plane() {
    let dir = std::env::temp_dir().join(format!("needle-plot-depth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = needle_e2e::example("anatomy");
    let file = file.to_str().unwrap();
    let plan = needle_e2e::needle_stdout(&["plan", file, "--json"]);
    let plan_path = dir.join("plan.json");
    std::fs::write(&plan_path, &plan).unwrap();
    let plan: serde_json::Value = serde_json::from_slice(&plan).unwrap();
    let points: Vec<[f64; 3]> = serde_json::from_value(plan["best"]["points"].clone()).unwrap();
    let mut marked_far = usize::MAX;
    for at in ["8,30.8,45", "-12,20,40"] {
        let out = dir.join("slices.svg");
        let slice_at = format!("--slice-at={at}");
        let args = ["plot", file, "--plan", plan_path.to_str().unwrap()];
        let mut args = args.to_vec();
        args.extend([slice_at.as_str(), "-o", out.to_str().unwrap()]);
        needle_e2e::needle_stdout(&args);
        let svg = std::fs::read_to_string(&out).unwrap();
        let at: Vec<f64> = at.split(',').map(|v| v.parse().unwrap()).collect();
        for p in panels(&svg) {
            let [h, v] = p.axes;
            let fixed = 3 - h - v;
            let mut marked: Vec<[f64; 2]> = p
                .elements(r#"polyline class="path in-slice""#)
                .iter()
                .flat_map(|e| attr(e, "points").split(' '))
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    p.world(x.parse().unwrap(), y.parse().unwrap())
                })
                .collect();
            marked.dedup_by(|a, b| (a[0] - b[0]).abs() < 1e-3 && (a[1] - b[1]).abs() < 1e-3);
            let near: Vec<&[f64; 3]> = points
                .iter()
                .filter(|q| (q[fixed] - at[fixed]).abs() <= 2.0)
                .collect();
            assert_eq!(marked.len(), near.len(), "plane {fixed} at {at:?}");
            for (m, q) in marked.iter().zip(&near) {
                assert!(
                    (m[0] - q[h]).abs() < 0.01 && (m[1] - q[v]).abs() < 0.01,
                    "{m:?} {q:?}"
                );
            }
            if fixed == 0 && at[0] < 0.0 {
                marked_far = marked.len();
                let nearest = points
                    .iter()
                    .map(|q| (q[0] - at[0]).abs())
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest > 15.0, "{nearest}");
            }
        }
    }
    assert_eq!(marked_far, 0);
    let _ = std::fs::remove_dir_all(&dir);
}
