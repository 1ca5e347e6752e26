//! `needle simulate --world`: the clinical world's keys in the JSON, repeated bit for bit for a
//! seed, changed key by key with `--perturb`, and bad names and values refused naming the key.

use needle_e2e::{example, needle_fails_with, needle_json, needle_stdout};
use needle_sim::WORLD_KEYS;

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

#[test]
fn the_clinical_world_repeats_bit_for_bit_and_prints_its_keys() {
    let args = [
        "simulate",
        &paper(),
        "--runs",
        "6",
        "--closed-loop",
        "--compare-open-loop",
        "--world",
        "clinical",
        "--perturb",
        "layer_depths_mm=20,45",
        "--json",
        "--detail",
    ];
    let run = |threads: &str| needle_stdout(&[&args[..], &["--threads", threads]].concat());
    let once = run("1");
    assert_eq!(once, run("2"), "the same seed, the same bits");
    let v: serde_json::Value = serde_json::from_slice(&once).unwrap();
    let w = &v["world"];
    assert_eq!(w.as_object().unwrap().len(), WORLD_KEYS.len() + 1);
    assert_eq!(w["tracker_dof"], 5);
    assert_eq!(w["layers"], 2, "--perturb over the preset");
    assert_eq!(w["layer_depths_mm"], serde_json::json!([20.0, 45.0]));
    assert_eq!(w["tracker_latency_ms"], 30.0);
    let drawn = &v["runs_detail"][0]["drawn"]["effects"];
    assert_eq!(drawn["layers"]["boundaries_mm"], w["layer_depths_mm"]);
    assert!(v["perturbation"].is_object() && v["controller"].is_object());
    // The default world draws no effect and says so.
    let plain = needle_json(&["simulate", &paper(), "--runs", "2", "--json", "--detail"]);
    assert!(plain["runs_detail"][0]["drawn"].get("effects").is_none());
    assert_eq!(plain["world"]["tracker_dof"], 6);
}

#[test]
fn bad_worlds_and_effects_are_clear_errors() {
    let paper_text = std::fs::read_to_string(paper()).unwrap();
    for (args, says) in [
        (vec!["--world", "lab"], "unknown world `lab`"),
        (
            vec!["--perturb", "layers=9"],
            "layers = 9 is outside [0, 8]",
        ),
        (vec!["--perturb", "tracker_dof=4"], "tracker_dof = 4"),
        (vec!["--perturb", "layers=1.5"], "a whole number"),
        (
            vec!["--perturb", "tracker_latency_ms=-3"],
            "tracker_latency_ms",
        ),
        (
            vec!["--perturb", "puncture_mm=x"],
            "puncture_mm: `x` is not a number",
        ),
        (
            vec!["--perturb", "latency=3"],
            "or a world effect: tracker_dof",
        ),
        (
            vec!["--perturb", "layer_depths_mm=30,10"],
            "layer_depths_mm: the depths must ascend",
        ),
    ] {
        let args = [&["simulate", "{}"][..], &args].concat();
        needle_fails_with(&paper_text, &args, says);
    }
}

#[test]
fn the_table_names_the_world_when_it_is_not_the_default() {
    let run = |world: &str| {
        let out = needle_stdout(&["simulate", &paper(), "--runs", "3", "--world", world]);
        String::from_utf8(out).unwrap()
    };
    assert!(run("clinical").contains("world: tracker_dof=5 tracker_bias_mm=0.3"));
    assert!(!run("default").contains("world:"));
}

/// A scenario's `[execution]` names its world as `--world` does: the same runs, bit for bit.
#[test]
fn a_scenario_names_its_world_as_the_flag_does() {
    let dir = std::env::temp_dir().join(format!("needle-world-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("paper-clinical.toml");
    let text = std::fs::read_to_string(paper()).unwrap();
    std::fs::write(
        &file,
        needle_e2e::with_execution(&text, "world = \"clinical\""),
    )
    .unwrap();
    let run = |path: &str, extra: &[&str]| {
        let args = [
            &["simulate", path, "--runs", "4", "--closed-loop", "--json"][..],
            extra,
        ];
        let v = needle_json(&args.concat());
        (v["world"].clone(), v["summary"].clone())
    };
    let from_file = run(file.to_str().unwrap(), &[]);
    assert_eq!(from_file, run(&paper(), &["--world", "clinical"]));
    assert_eq!(from_file.0["tracker_dof"], 5);
    let replaced = run(file.to_str().unwrap(), &["--world", "default"]);
    assert_eq!(
        replaced.0["tracker_dof"], 6,
        "--world replaces the file's world"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
