//! `needle benchmark` end to end, kept short (3 generated scenarios, 4 worlds each): the JSON's
//! rows and totals, the scenarios it writes (they plan with `needle plan`), repeatability over
//! thread counts, and bad input refused as usage errors.

use needle_e2e::{json_keys, needle, needle_json};
use serde_json::Value;

const SHORT: [&str; 7] = [
    "benchmark",
    "--scenarios",
    "3",
    "--runs",
    "4",
    "--seed",
    "101",
];

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn u(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

fn scratch(test: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-benchmark-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Every rate a percentage, and the closed loop's counts adding up to the runs.
fn check_figures(v: &Value, runs: u64) {
    let (o, c) = (&v["open_loop"], &v["closed_loop"]);
    for rate in [&o["hit_percent"], &c["reached_percent"]] {
        assert!((0.0..=100.0).contains(&f(rate)), "{v}");
    }
    assert!(u(&o["hits"]) <= runs);
    assert_eq!(u(&c["arrived"]) + u(&c["stops"]), runs, "{v}");
    // Every run ends one way, judged on the true tip and path.
    let ends = ["reached", "missed", "collided", "stopped"];
    assert_eq!(ends.iter().map(|k| u(&c[k])).sum::<u64>(), runs, "{v}");
    let by_reason: u64 = c["stop_reasons"].as_object().unwrap().values().map(u).sum();
    assert_eq!(by_reason, u(&c["stops"]));
    assert!((f(&o["hit_percent"]) - 100.0 * u(&o["hits"]) as f64 / runs as f64).abs() < 1e-9);
    assert!(f(&o["mean_target_error"]) > 0.0);
    if u(&c["arrived"]) > 0 {
        assert!(f(&c["mean_target_error"]) <= f(&c["p95_target_error"]) + 1e-9);
    } else {
        assert!(c["mean_target_error"].is_null());
    }
}

#[test]
fn rows_and_totals_add_up_and_the_written_scenarios_plan() {
    let dir = scratch("rows");
    let out = needle()
        .args(SHORT)
        .args(["--threads", "2", "--json", "--write-scenarios"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    // Progress is for a terminal: piped, with --json, stderr says nothing of the scenarios.
    assert!(!err.contains("scenario "), "{err}");
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        json_keys(&v),
        [
            "by_form",
            "controller",
            "faults",
            "generator",
            "perturbation",
            "scenarios",
            "totals",
            "unplanned",
            "world"
        ]
    );
    let rows = v["scenarios"].as_array().unwrap();
    let unplanned = v["unplanned"].as_array().unwrap();
    assert_eq!(rows.len() + unplanned.len(), 3);
    let t = &v["totals"];
    assert_eq!(
        (u(&t["scenarios"]), u(&t["planned"]), u(&t["unplanned"])),
        (3, rows.len() as u64, unplanned.len() as u64)
    );
    let sum = |path: [&str; 2]| -> u64 { rows.iter().map(|r| u(&r[path[0]][path[1]])).sum() };
    let closed = ["reached", "missed", "collided", "arrived", "stops", "hits"];
    let closed = closed.iter().map(|k| ["closed_loop", k]);
    for path in std::iter::once(["open_loop", "hits"]).chain(closed) {
        assert_eq!(u(&t[path[0]][path[1]]), sum(path), "{path:?}");
    }
    let runs: u64 = rows.iter().map(|r| u(&r["runs"])).sum();
    assert_eq!(u(&t["runs"]), runs);
    // The total's mean is over every run: the rows' means weighted by their runs.
    let weighted: f64 = rows
        .iter()
        .map(|r| f(&r["open_loop"]["mean_target_error"]) * f(&r["runs"]))
        .sum();
    assert!((f(&t["open_loop"]["mean_target_error"]) - weighted / runs as f64).abs() < 1e-6);
    check_figures(t, runs);
    // The totals by form partition the rows: open loop by the open-loop plan's form, closed
    // loop by the steered plan's.
    let by_form = v["by_form"].as_object().unwrap();
    for (form, ft) in by_form {
        let open: Vec<&Value> = rows.iter().filter(|r| r["form"] == form.as_str()).collect();
        assert_eq!(u(&ft["scenarios"]), open.len() as u64, "{form}");
        assert_eq!(u(&ft["runs"]), 4 * open.len() as u64, "{form}");
        let steered: Vec<&Value> = rows
            .iter()
            .filter(|r| r["closed_loop_plan"]["form"] == form.as_str())
            .collect();
        assert_eq!(u(&ft["closed_loop_scenarios"]), steered.len() as u64);
        if steered.is_empty() {
            assert!(ft["closed_loop"].is_null(), "{form}");
            continue;
        }
        let reached: u64 = steered
            .iter()
            .map(|r| u(&r["closed_loop"]["reached"]))
            .sum();
        let c = &ft["closed_loop"];
        assert_eq!(u(&c["reached"]), reached, "{form}");
        assert_eq!(u(&c["arrived"]) + u(&c["stops"]), 4 * steered.len() as u64);
    }
    let counted: u64 = by_form.values().map(|ft| u(&ft["scenarios"])).sum();
    assert_eq!(counted, rows.len() as u64);
    let steered: u64 = by_form
        .values()
        .map(|ft| u(&ft["closed_loop_scenarios"]))
        .sum();
    assert_eq!(steered, rows.len() as u64);
    for row in rows {
        let reserve = f(&row["closed_loop_plan"]["curvature_reserve"]);
        assert!(reserve == 0.2 || reserve == 0.1, "{row}");
    }
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(u(&row["runs"]), 4);
        check_figures(row, 4);
        let seed = u(&row["seed"]);
        assert_eq!(seed, 101 + k as u64, "rows in seed order");
        let file = dir.join(format!("unseen-{seed}.toml"));
        let plan = needle_json(&["plan", file.to_str().unwrap(), "--json"]);
        assert_eq!(plan["best"]["form"], row["form"], "{}", file.display());
        let length = f(&plan["best"]["length"]);
        assert!((length - f(&row["plan_length"])).abs() < 1e-3);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The planted family: every scenario has a path (none unplanned), its files are named after
/// the family and plan with `needle plan`, and the steered plans keep the bound.
#[test]
fn planted_scenarios_all_plan_and_are_written_under_their_name() {
    let dir = scratch("planted");
    let v = needle_json(&[
        "benchmark",
        "--generator",
        "planted",
        "--scenarios",
        "3",
        "--runs",
        "2",
        "--seed",
        "201",
        "--closed-loop-max-collision-probability",
        "0.01",
        "--json",
        "--write-scenarios",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(v["generator"], "planted");
    assert_eq!(v["unplanned"].as_array().unwrap().len(), 0, "{v}");
    let rows = v["scenarios"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for row in rows {
        assert!(row["closed_loop_refused"].is_null(), "{row}");
        let file = dir.join(format!("planted-{}.toml", u(&row["seed"])));
        let plan = needle_json(&["plan", file.to_str().unwrap(), "--json"]);
        assert_eq!(plan["best"]["form"], row["form"], "{}", file.display());
        assert!(!dir
            .join(format!("unseen-{}.toml", u(&row["seed"])))
            .exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_table_and_the_json_repeat_on_any_thread_count() {
    let run = |threads: &str, json: bool| {
        let mut c = needle();
        c.args(SHORT).args(["--threads", threads]);
        if json {
            c.arg("--json");
        }
        let out = c.output().unwrap();
        assert!(out.status.success());
        String::from_utf8(out.stdout).unwrap()
    };
    assert_eq!(run("1", true), run("2", true));
    let table = run("2", false);
    assert!(
        table.contains("closed loop") && table.contains("total: "),
        "{table}"
    );
    assert_eq!(table.lines().filter(|l| l.starts_with("   10")).count(), 3);
}

#[test]
fn bad_counts_and_perturbations_are_refused_without_a_panic() {
    for (flag, value, status) in [
        ("--scenarios", "0", 2),
        ("--runs", "0", 2),
        ("--threads", "0", 2),
        ("--perturb", "curvature_spread=-1", 1),
        ("--perturb", "no_such_key=1", 1),
    ] {
        let out = needle()
            .args(["benchmark", "--scenarios", "1", "--runs", "1", flag, value])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(status), "{flag} {value}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(out.stdout.is_empty(), "{flag} {value}");
    }
}
