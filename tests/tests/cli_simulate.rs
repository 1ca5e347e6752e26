//! `needle simulate` end to end: the JSON contract, repeatability over thread counts, the plot,
//! the table, and bad input.

use needle_e2e::{example, json_keys, needle, needle_json};
use needle_sim::KEYS;
use serde_json::Value;

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

#[test]
fn json_has_exactly_the_contracted_keys() {
    let v = needle_json(&["simulate", &paper(), "--runs", "8", "--json"]);
    assert_eq!(
        json_keys(&v),
        [
            "closed_loop",
            "perturbation",
            "plan",
            "runs",
            "summary",
            "world"
        ]
    );
    assert_eq!(v["plan"]["form"], "RL");
    assert_eq!(v["runs"], 8);
    assert_eq!(v["closed_loop"], false);
    let p = &v["perturbation"];
    assert_eq!(json_keys(p).len(), 11);
    assert_eq!(p["measure_every_mm"], 1.0);
    let s = &v["summary"];
    assert_eq!(
        json_keys(s),
        [
            "collisions",
            "min_clearance",
            "path_deviation",
            "rotations",
            "target_error"
        ]
    );
    assert_eq!(
        json_keys(&s["rotations"]),
        [
            "max_per_run",
            "mean_total_deg",
            "median_per_run",
            "smallest_deg"
        ]
    );
    assert_eq!(json_keys(&s["target_error"]), ["max", "mean", "p95", "rms"]);
    assert_eq!(json_keys(&s["path_deviation"]), ["max", "rms"]);
    let t = &s["target_error"];
    let f = |x: &Value| x.as_f64().unwrap();
    assert!(f(&t["mean"]) > 0.0 && f(&t["mean"]) <= f(&t["rms"]) + 1e-12);
    assert!(f(&t["p95"]) <= f(&t["max"]));
    assert!(f(&s["path_deviation"]["rms"]) > 0.1);
}

#[test]
fn detail_repeats_bit_for_bit_on_any_thread_count() {
    let run = |threads: &str| {
        let out = needle()
            .args([
                "simulate",
                &paper(),
                "--runs",
                "6",
                "--seed",
                "40",
                "--form",
                "LRR",
            ])
            .args(["--json", "--detail", "--threads", threads])
            .output()
            .unwrap();
        assert!(out.status.success());
        out.stdout
    };
    let one = run("1");
    assert_eq!(one, run("2"));
    let v: Value = serde_json::from_slice(&one).unwrap();
    let runs = v["runs_detail"].as_array().unwrap();
    assert_eq!(runs.len(), 6);
    for (i, r) in runs.iter().enumerate() {
        assert_eq!(r["seed"], 40 + i as u64);
        for k in [
            "target_error",
            "path_rms",
            "min_clearance",
            "collided",
            "drawn",
        ] {
            assert!(!r[k].is_null(), "{k}");
        }
        let ops: Vec<&str> = r["steps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["op"].as_str().unwrap())
            .collect();
        assert_eq!(ops, ["insert_spin", "rotate", "insert", "rotate", "insert"]);
        let pts = r["points"].as_array().unwrap();
        assert!(pts.len() > 90);
        for w in pts.windows(2) {
            let d: f64 = (0..3)
                .map(|k| (w[1][k].as_f64().unwrap() - w[0][k].as_f64().unwrap()).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d <= 1.0 + 1e-4);
        }
    }
}

#[test]
fn zero_perturbation_gives_zero_deviation() {
    let mut args: Vec<String> = ["simulate", &paper(), "--runs", "3", "--json"]
        .map(String::from)
        .to_vec();
    for k in KEYS.iter().filter(|k| **k != "measure_every_mm") {
        args.push("--perturb".into());
        args.push(format!("{k}=0"));
    }
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let v = needle_json(&refs);
    let s = &v["summary"];
    assert!(s["path_deviation"]["max"].as_f64().unwrap() < 1e-3);
    assert!(s["target_error"]["max"].as_f64().unwrap() < 1e-3);
    assert_eq!(s["collisions"], 0);
}

#[test]
fn table_and_plot() {
    let dir = std::env::temp_dir().join(format!("needle-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("sim.svg");
    let out = needle()
        .args([
            "simulate",
            example("space").to_str().unwrap(),
            "--runs",
            "5",
        ])
        .arg("--plot")
        .arg(&svg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.starts_with("simulated open-loop insertions of R in space.toml"),
        "{text}"
    );
    assert!(text.contains("target error") && text.contains("collisions:"));
    let drawing = std::fs::read_to_string(&svg).unwrap();
    // Both projections of a 3-D scenario: the tube and the plan twice.
    assert_eq!(drawing.matches(r#"class="executed""#).count(), 2);
    assert_eq!(drawing.matches(r#"class="path best""#).count(), 2);
    assert!(drawing.contains("5 simulated"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_input_is_a_clear_error() {
    for (args, says) in [
        (
            vec!["--perturb", "stiffness=2"],
            "unknown perturbation `stiffness`",
        ),
        (
            vec!["--perturb", "curvature_spread=-0.1"],
            "curvature_spread = -0.1 is outside [0, 0.5]",
        ),
        (
            vec!["--perturb", "measure_every_mm=0"],
            "measure_every_mm = 0 is outside [0.05, 1]",
        ),
        (
            vec!["--perturb", "measure_every_mm=0.00001"],
            "measure_every_mm = 0.00001 is outside [0.05, 1]",
        ),
        (
            vec!["--perturb", "entry_position_mm=nan"],
            "entry_position_mm = NaN",
        ),
        (vec!["--perturb", "tracker_heading_deg"], "is not KEY=VALUE"),
        (vec!["--form", "XX"], "form"),
        (vec!["--form", "L"], "the target is unreachable"),
        (vec!["--runs", "0"], "--runs must be at least 1"),
    ] {
        let out = needle()
            .args(["simulate", &paper()])
            .args(&args)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

fn svg_of(args: &[&str], dir: &std::path::Path, name: &str) -> String {
    let svg = dir.join(name);
    let out = needle()
        .args(["simulate", &paper()])
        .args(args)
        .arg("--plot")
        .arg(&svg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::read_to_string(&svg).unwrap()
}

/// The plot says what it shows: closed loop is not called open loop, runs stopped before the
/// target are drawn apart (dashed, their own legend entry), and `--compare-open-loop` draws the
/// open-loop paths too, in their own colour and legend entry.
#[test]
fn the_plot_tells_open_closed_and_stopped_runs_apart() {
    let dir = std::env::temp_dir().join(format!("needle-sim-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let closed = svg_of(&["--runs", "3", "--closed-loop"], &dir, "closed.svg");
    assert!(
        !closed.contains("open loop"),
        "closed loop called open loop"
    );
    assert!(closed.contains("closed loop, not stopped (reached, missed or collided): 3 of 3 runs"));
    assert_eq!(closed.matches(r#"class="executed""#).count(), 1);
    let compare = ["--runs", "3", "--closed-loop", "--compare-open-loop"];
    let both = svg_of(&compare, &dir, "compare.svg");
    assert_eq!(both.matches(r#"class="executed open-loop""#).count(), 1);
    assert!(both.contains("open loop, same worlds: 3 of 3 runs"));
    assert_eq!(both.matches(r#"class="executed""#).count(), 1);
    let faults = [
        "--runs",
        "2",
        "--closed-loop",
        "--fault",
        "dropout_rate=1",
        "--fault",
        "dropout_mm=50",
    ];
    let stopped = svg_of(&faults, &dir, "stopped.svg");
    assert_eq!(stopped.matches(r#"class="executed stopped""#).count(), 1);
    assert!(stopped.contains("stopped before the target: 2 of 2 runs"));
    assert!(stopped.contains("stroke-dasharray:4 2"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An output path that cannot be written fails before the simulation, not after it; a plot file
/// the command created is not left behind empty when the simulation fails.
#[test]
fn the_plot_file_is_opened_before_simulating() {
    // Nothing listens on port 1: steering there fails at once, but only once the runs start.
    let device = ["--closed-loop", "--tcp", "127.0.0.1:1"];
    let out = needle()
        .args(["simulate", &paper()])
        .args(device)
        .args(["--plot", "/nonexistent-folder/sim.svg"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cannot write /nonexistent-folder/sim.svg"),
        "{err}"
    );
    let svg = std::env::temp_dir().join(format!("needle-sim-unmade-{}.svg", std::process::id()));
    let out = needle()
        .args(["simulate", &paper()])
        .args(device)
        .arg("--plot")
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot connect"));
    assert!(!svg.exists(), "an empty plot was left behind");
}

/// Flags that would be silently ignored are usage errors (exit status 2, as clap's).
#[test]
fn flags_that_would_do_nothing_are_refused() {
    for (args, says) in [
        (vec!["--detail"], "--json"),
        (vec!["--threads", "0"], "must be at least 1"),
    ] {
        let out = needle()
            .args(["simulate", &paper()])
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
    }
}

/// The help says what `simulate` does now: open loop or closed loop.
#[test]
fn help_names_both_loops() {
    for args in [vec!["--help"], vec!["simulate", "--help"]] {
        let out = needle().args(&args).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        let line = text
            .lines()
            .find(|l| l.contains("simulated perturbed insertions"))
            .unwrap_or_else(|| panic!("{args:?}: {text}"));
        assert!(!line.contains("(open loop)"), "{line}");
        assert!(line.contains("closed loop"), "{line}");
    }
}
