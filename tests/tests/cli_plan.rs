//! `needle plan` end to end: the JSON contract, the table, restrictions and errors.

use needle_e2e::{example, needle, needle_fails_with, needle_json, TempScenario};
use serde_json::Value;
use std::fmt::Write;

fn plan_json(args: &[&str]) -> Value {
    needle_json(&[&["plan"], args, &["--json"]].concat())
}

fn dist(a: &Value, b: [f64; 3]) -> f64 {
    let p: Vec<f64> = a
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    ((p[0] - b[0]).powi(2) + (p[1] - b[1]).powi(2) + (p[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn paper_json_has_the_contracted_keys_and_a_dense_path() {
    let v = plan_json(&[example("paper").to_str().unwrap()]);
    let best = &v["best"];
    assert_eq!(best["form"], "RL");
    assert_eq!(best["feasible"], true);
    for key in [
        "length",
        "risk",
        "penalty",
        "control_degree",
        "objective",
        "min_clearance",
        "target_error",
    ] {
        assert!(best[key].is_number(), "best.{key}");
    }
    assert_eq!(best["control_degree"], 2);
    assert!(best["insertion"]["theta1_deg"].is_number());
    let segs = best["segments"].as_array().unwrap();
    assert_eq!(segs.len(), 2);
    assert_eq!(segs[0]["kind"], "R");
    assert_eq!(segs[1]["kind"], "L");
    for s in segs {
        assert!(s["length"].is_number() && s["bevel_deg"].is_number());
    }
    let pts = best["points"].as_array().unwrap();
    assert!(dist(&pts[0], [0.0, 0.0, 0.0]) < 1e-6);
    assert!(dist(&pts[pts.len() - 1], [0.0, 0.0, 90.0]) <= 0.1);
    let mut walked = 0.0;
    for w in pts.windows(2) {
        let p: Vec<f64> = w[1]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let step = dist(&w[0], [p[0], p[1], p[2]]);
        assert!(step <= 1.0 + 1e-4, "points {step} mm apart");
        walked += step;
    }
    let length = best["length"].as_f64().unwrap();
    assert!(
        (walked - length).abs() < 0.05 * length,
        "polyline {walked} vs length {length}"
    );
    let forms = v["forms"].as_array().unwrap();
    assert_eq!(forms.len(), 10);
    let l = forms.iter().find(|f| f["form"] == "L").unwrap();
    assert_eq!(l["feasible"], false);
    assert!(l["length"].is_null() && l["objective"].is_null() && l["min_clearance"].is_null());
    assert!(v["stats"]["time_us"].is_number() && v["stats"]["iterations"].as_u64().unwrap() > 0);
}

#[test]
fn forms_and_degree_flags_restrict_the_search() {
    let p = example("paper");
    let v = plan_json(&[p.to_str().unwrap(), "--forms", "RL,LRL"]);
    let words: Vec<&str> = v["forms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["form"].as_str().unwrap())
        .collect();
    assert_eq!(words, ["RL", "LRL"]);
    let v = plan_json(&[p.to_str().unwrap(), "--max-degree", "1"]);
    assert_eq!(v["forms"].as_array().unwrap().len(), 2);
    assert_eq!(v["best"]["form"], "R");
}

#[test]
fn table_lists_every_form_and_the_best() {
    let out = needle().arg("plan").arg(example("paper")).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for w in ["RRR", "LRL", "best: RL (N = 2)"] {
        assert!(text.contains(w), "{w} missing from\n{text}");
    }
}

#[test]
fn the_3d_example_needs_a_bevel_rotation() {
    let v = plan_json(&[example("space").to_str().unwrap()]);
    let best = &v["best"];
    assert_eq!(best["feasible"], true);
    assert!(best["target_error"].as_f64().unwrap() <= 0.1);
    assert!(best["min_clearance"].as_f64().unwrap() > 0.0);
    // Out of the plane: some arc is rolled by an angle that is neither 0 nor 180 degrees.
    let rolled = best["segments"].as_array().unwrap().iter().any(|s| {
        let b = s["bevel_deg"].as_f64().unwrap().abs();
        s["kind"] == "R" && b > 1.0 && (180.0 - b) > 1.0
    });
    assert!(rolled, "{best}");
    let xs: Vec<f64> = best["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p[0].as_f64().unwrap())
        .collect();
    assert!(
        xs.iter().any(|x| x.abs() > 1.0),
        "the path leaves the y-z plane"
    );
}

fn scenario_file(text: &str) -> TempScenario {
    TempScenario::new(text)
}

fn paper_with(extra_obstacles: &str) -> String {
    let base = std::fs::read_to_string(example("paper")).unwrap();
    format!("{base}\n{extra_obstacles}")
}

fn fails_with(text: &str, needle_text: &str) {
    needle_fails_with(text, &["plan", "{}"], needle_text);
}

#[test]
fn bad_scenarios_exit_non_zero_with_the_reason() {
    let mut many = String::new();
    // The paper's three and 510 more: one over the host's capacity (counted before any is read).
    for i in 0..planner_core::HOST_MAX_OBSTACLES - 2 {
        writeln!(
            many,
            "[[obstacles]]\ncenter = [0.0, {}, 200.0]\nradius = 1.0",
            -100.0 + 5.0 * i as f32
        )
        .unwrap();
    }
    fails_with(
        &paper_with(&many),
        "513 obstacles given but the planner holds at most 512",
    );
    fails_with(
        &paper_with("[[obstacles]]\ncenter = [0.0, 0.0, 88.0]\nradius = 5.0"),
        "the target lies inside obstacle 3",
    );
    fails_with(
        &std::fs::read_to_string(example("paper"))
            .unwrap()
            .replace("radius = 11.0", "radius = nan"),
        "obstacles[1].radius is not a finite number",
    );
    fails_with(
        &std::fs::read_to_string(example("paper"))
            .unwrap()
            .replace("curvature_radius = 63.7", "curvature_radius = -2"),
        "needle.curvature_radius must be positive",
    );
    let walled = paper_with(
        "[[obstacles]]\ncenter = [0.0, 0.0, 75.0]\nradius = 12.0\n[[obstacles]]\ncenter = [0.0, 14.0, 92.0]\nradius = 12.0\n\
         [[obstacles]]\ncenter = [0.0, -14.0, 92.0]\nradius = 12.0\n[[obstacles]]\ncenter = [0.0, 0.0, 106.0]\nradius = 12.0",
    );
    fails_with(&walled, "unreachable");
    let out = needle()
        .args(["plan", "no/such/file.toml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read scenario"));
    let out = needle()
        .arg("plan")
        .arg(example("paper"))
        .args(["--forms", "RLL"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("is not a path form"));
}

#[test]
fn schedule_flag_prints_the_schedule_table_after_the_plan() {
    let p = example("paper");
    let run = |extra: &[&str]| {
        let out = needle().arg("plan").arg(&p).args(extra).output().unwrap();
        assert!(out.status.success());
        String::from_utf8(out.stdout).unwrap()
    };
    let plain = run(&[]);
    assert!(!plain.contains("schedule"), "{plain}");
    let text = run(&["--schedule", "--forms", "LRR"]);
    let at = |w: &str| {
        text.find(w)
            .unwrap_or_else(|| panic!("{w} missing from\n{text}"))
    };
    assert!(at("best: LRR") < at("schedule (driver: insert 2.5 mm/s"));
    assert!(at("schedule (driver:") < at("posture: entry (0.00, 0.00, 0.00) mm"));
    assert!(at("posture:") < at("step  op"));
    for w in [
        "angle (deg)",
        "length (mm)",
        "turns",
        "duration (s)",
        "roll 0.0 deg",
    ] {
        at(w);
    }
    // LRR: spin the line in, then per arc a half turn of the bevel and a push.
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip_while(|l| !l.starts_with("step  op"))
        .skip(1)
        .take_while(|l| !l.starts_with("total"))
        .map(|l| l.split_whitespace().collect())
        .collect();
    let ops: Vec<&str> = rows.iter().map(|r| r[1]).collect();
    assert_eq!(ops, ["insert_spin", "rotate", "insert", "rotate", "insert"]);
    assert_eq!(rows[1][2], "180.0");
    assert_eq!(
        rows[0][4].parse::<u32>().unwrap() % 2,
        0,
        "whole, even turns"
    );
    assert!(at("total ") > at("step  op") && text.contains("s, peak twist 360.0 deg"));
}

/// Every `best.schedule` step has exactly the keys its `op` promises.
fn assert_schedule_keys(v: &Value) -> Vec<String> {
    let s = &v["best"]["schedule"];
    for key in ["duration_s", "max_twist_deg"] {
        assert!(s[key].is_number(), "schedule.{key}: {s}");
    }
    let posture = s["posture"].as_object().expect("schedule.posture");
    let mut keys: Vec<&str> = posture.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        ["direction", "entry", "roll_deg", "theta1_deg", "theta2_deg"]
    );
    assert_eq!(posture["theta1_deg"], v["best"]["insertion"]["theta1_deg"]);
    let mut total = 0.0;
    let mut ops = Vec::new();
    for step in s["steps"].as_array().expect("schedule.steps") {
        let op = step["op"].as_str().unwrap().to_string();
        let mut keys: Vec<&str> = step
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        keys.sort_unstable();
        let want: &[&str] = match op.as_str() {
            "rotate" => &["angle_deg", "duration_s", "op"],
            "insert" => &["duration_s", "length_mm", "op"],
            "insert_spin" => &["duration_s", "length_mm", "op", "turns"],
            "insert_duty" => &["duration_s", "duty", "length_mm", "op"],
            other => panic!("unknown op {other}"),
        };
        assert_eq!(keys, want, "{step}");
        total += step["duration_s"].as_f64().unwrap();
        ops.push(op);
    }
    let duration = s["duration_s"].as_f64().unwrap();
    assert!(
        (total - duration).abs() < 1e-3 * duration,
        "{total} vs {duration}"
    );
    assert!(s["max_twist_deg"].as_f64().unwrap() <= 360.0);
    ops
}

#[test]
fn json_best_schedule_has_the_contracted_keys() {
    let paper = example("paper");
    let v = plan_json(&[paper.to_str().unwrap()]);
    assert_eq!(assert_schedule_keys(&v), ["insert", "insert_spin"]);
    // The pushes are the segments' lengths, at the driver's insertion speed (2.5 mm/s).
    let steps = v["best"]["schedule"]["steps"].as_array().unwrap();
    for (step, seg) in steps.iter().zip(v["best"]["segments"].as_array().unwrap()) {
        assert_eq!(step["length_mm"], seg["length"]);
    }
    let push = steps[0]["length_mm"].as_f64().unwrap() as f32 / 2.5;
    assert_eq!(steps[0]["duration_s"].as_f64().unwrap(), f64::from(push));
    let v = plan_json(&[paper.to_str().unwrap(), "--forms", "LRR"]);
    assert_eq!(
        assert_schedule_keys(&v),
        ["insert_spin", "rotate", "insert", "rotate", "insert"]
    );
    let v = plan_json(&[example("space").to_str().unwrap()]);
    assert_schedule_keys(&v);
    // Out of the plane the first arc's roll is set with the posture, before the needle enters.
    assert_eq!(
        v["best"]["schedule"]["posture"]["roll_deg"],
        v["best"]["segments"][0]["bevel_deg"]
    );
}

#[test]
fn a_bad_driver_setting_names_the_key() {
    let with_driver = |table: &str| paper_with(&format!("[driver]\n{table}"));
    fails_with(
        &with_driver("insert_speed = 0"),
        "driver.insert_speed must be positive",
    );
    fails_with(
        &with_driver("rotate_speed = -90"),
        "driver.rotate_speed must be positive",
    );
    fails_with(
        &with_driver("spin_rate = 0.0"),
        "driver.spin_rate must be positive",
    );
    fails_with(
        &with_driver("max_twist_deg = 100"),
        "driver.max_twist_deg is out of range: allowed is at least 360 degrees",
    );
    fails_with(&with_driver("speed = 3"), "unknown field `speed`");
    // The defaults, written out, plan as the absent table does.
    let defaults =
        "insert_speed = 2.5\nrotate_speed = 360.0\nspin_rate = 4.0\nmax_twist_deg = 360.0";
    let f = scenario_file(&with_driver(defaults));
    let mut a = plan_json(&[f.0.to_str().unwrap()]);
    let mut b = plan_json(&[example("paper").to_str().unwrap()]);
    a.as_object_mut().unwrap().remove("stats");
    b.as_object_mut().unwrap().remove("stats");
    assert_eq!(a, b);
}

/// The paper's scenario with a big sphere in front of the target and only straight lines allowed:
/// no form can reach it.
fn blocked_lines_only() -> TempScenario {
    let text = std::fs::read_to_string(example("paper"))
        .unwrap()
        .replace("[planner]\n", "[planner]\nforms = [\"L\"]\n");
    TempScenario::new(&format!(
        "{text}\n[[obstacles]]\ncenter = [0.0, 0.0, 70.0]\nradius = 15.0\n"
    ))
}

#[test]
fn a_plan_with_no_feasible_form_prints_every_form_and_no_best_and_exits_1() {
    let scenario = blocked_lines_only();
    let out = needle()
        .args(["plan", scenario.0.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("the target is unreachable"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let v: Value = serde_json::from_slice(&out.stdout).expect("the JSON report on stdout");
    assert!(v["best"].is_null(), "{}", v["best"]);
    let forms = v["forms"].as_array().unwrap();
    assert_eq!(forms.len(), 1);
    assert_eq!(forms[0]["form"], "L");
    assert_eq!(forms[0]["feasible"], false);
    assert_eq!(forms[0]["status"], "Infeasible");
    assert!(
        forms[0]["evaluations"].as_u64().unwrap() > 0,
        "the form was tried"
    );
    assert!(v["stats"]["time_us"].is_number());

    let out = needle()
        .args(["plan", scenario.0.to_str().unwrap(), "--schedule"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        table.contains("form") && table.contains("Infeasible"),
        "{table}"
    );
    assert!(
        !table.contains("best:") && !table.contains("schedule ("),
        "{table}"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("the target is unreachable"), "{err}");
}

/// `cargo xtask device-bench`'s "space" workload is the 3-D example's scene, planned unbounded at the
/// full curvature: only those two keys differ from examples/space.toml.
#[test]
fn the_device_bench_space_workload_is_the_example_unbounded() {
    let load = |p: &std::path::Path| needle_scenario::load_scenario(p).unwrap();
    let example = load(&needle_e2e::example("space"));
    let workload = load(&needle_e2e::workspace().join("devtools/workloads/space.toml"));
    assert_eq!(example.options.curvature_reserve, 0.2);
    assert_eq!(workload.options.curvature_reserve, 0.0);
    let mut same = example.clone();
    same.options.curvature_reserve = 0.0;
    assert_eq!(same, workload);
    let e = needle_scenario::execution::load_execution(
        &needle_e2e::workspace().join("devtools/workloads/space.toml"),
    )
    .unwrap();
    assert_eq!(e.max_collision_probability, None);
}
