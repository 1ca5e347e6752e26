//! The scenario's `[steering]` table reaches the controller `needle simulate` steers with, and
//! only the controller: the world stays what `[execution]` and `--perturb` make it.

use needle_e2e::{example, needle, needle_json};
use serde_json::Value;

/// A folder of this test process's own for the scenario files.
fn scratch(test: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-steering-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The paper's scenario with `table` appended, in `dir`.
fn paper_with(dir: &std::path::Path, name: &str, table: &str) -> String {
    let text = std::fs::read_to_string(example("paper")).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, format!("{text}\n{table}")).unwrap();
    path.to_str().unwrap().to_string()
}

fn summary(file: &str, extra: &[&str]) -> Value {
    let mut args = vec!["simulate", file, "--closed-loop", "--json"];
    args.extend_from_slice(extra);
    needle_json(&args)["summary"].clone()
}

/// A tracker three times as noisy as the defaults assume: a controller told so rejects no fix
/// as an outlier and lands closer than one that assumes the defaults.
#[test]
fn a_controller_told_the_trackers_noise_uses_every_fix() {
    let dir = scratch("noise");
    let told = paper_with(&dir, "told.toml", "[steering]\ntracker_position_mm = 1.5\n");
    let world = ["--runs", "20", "--perturb", "tracker_position_mm=1.5"];
    let untold = summary(&example("paper").to_string_lossy(), &world);
    let told = summary(&told, &world);
    let outliers = |s: &Value| s["outliers"].as_u64().unwrap();
    let mean = |s: &Value| s["target_error"]["mean"].as_f64().unwrap();
    assert!(outliers(&untold) > 100, "{untold}");
    assert_eq!(outliers(&told), 0, "{told}");
    assert!(mean(&told) < mean(&untold), "{told} against {untold}");
}

/// The gap after which tracking counts as lost is the lab's to set: 5 mm dropouts are bridged
/// by the default 10 mm and stop runs at 3 mm.
#[test]
fn the_tracking_gap_is_the_labs_to_set() {
    let dir = scratch("gap");
    let short = paper_with(&dir, "gap.toml", "[steering]\ntracking_lost_after_mm = 3\n");
    let faults = [
        "--runs",
        "10",
        "--fault",
        "dropout_rate=0.02",
        "--fault",
        "dropout_mm=5",
    ];
    let lost = |s: &Value| s["stops"]["tracking_lost"].as_u64().unwrap();
    let default = summary(&example("paper").to_string_lossy(), &faults);
    let short = summary(&short, &faults);
    assert!(
        lost(&short) >= lost(&default) + 5,
        "{short} against {default}"
    );
    // The flag says the same as the table.
    let mut flagged = faults.to_vec();
    flagged.extend(["--steer", "tracking_lost_after_mm=3"]);
    let by_flag = summary(&example("paper").to_string_lossy(), &flagged);
    assert_eq!(by_flag, short);
    // What the controller was told is printed beside the world: the file's, then the flag's.
    let gap = dir.join("gap.toml");
    let args = ["simulate", gap.to_str().unwrap(), "--closed-loop", "--json"];
    let args = [&args[..], &["--runs", "1", "--steer", "target_mm=0.25"]].concat();
    let told = needle_json(&args)["controller"].clone();
    assert_eq!(told["tracking_lost_after_mm"], 3.0, "{told}");
    assert_eq!(told["target_mm"], 0.25, "{told}");
}

#[test]
fn a_bad_steering_key_is_a_clear_error() {
    let dir = scratch("bad");
    for (table, says) in [
        (
            "[steering]\ntracker_noise = 1\n",
            "steering.tracker_noise: unknown steering key",
        ),
        (
            "[steering]\nreach_tolerance_mm = -1\n",
            "steering.reach_tolerance_mm = -1",
        ),
    ] {
        let file = paper_with(&dir, "bad.toml", table);
        let out = needle()
            .args(["simulate", &file, "--closed-loop"])
            .output()
            .unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{table}: {err}");
    }
    let ok = paper_with(&dir, "ok.toml", "");
    let out = needle()
        .args(["simulate", &ok, "--closed-loop"])
        .args(["--steer", "tracker_position_mm=-2"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--steer") && err.contains("tracker_position_mm = -2"),
        "{err}"
    );
    let out = needle()
        .args(["simulate", &ok, "--steer", "iterations=3"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "--steer without --closed-loop");
}
