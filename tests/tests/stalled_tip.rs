//! A membrane that holds the tip while the needle is pushed (a stall of several millimetres,
//! then the jump when it gives) is not a lost tip: the rejected fixes lag along the path already
//! travelled, and the run is steered on to the target. These clinical-world runs stopped as
//! `tracking_lost` before the estimator told a held tip from a lost one
//! (docs/journal/2026-12-05.md, "A tip held by a membrane").

use needle_e2e::{example, needle_json, twice_clinical_flags};

#[test]
fn a_tip_held_by_a_membrane_is_steered_on_to_the_target() {
    for (name, seed) in [
        ("paper-clinical", 352),
        ("space-clinical", 11),
        ("space-clinical", 543),
    ] {
        let file = example(name);
        let seed = seed.to_string();
        let v = needle_json(&[
            "simulate",
            file.to_str().unwrap(),
            "--closed-loop",
            "--world",
            "clinical",
            "--runs",
            "1",
            "--seed",
            &seed,
            "--json",
            "--detail",
        ]);
        let run = &v["runs_detail"][0];
        let stalls = run["drawn"]["effects"]["layers"]["stalls_mm"]
            .as_array()
            .unwrap();
        let longest = stalls.iter().filter_map(|s| s.as_f64()).fold(0.0, f64::max);
        assert!(
            longest > 3.5,
            "{name} {seed}: the world held the tip {longest} mm"
        );
        assert!(run["stop_reason"].is_null(), "{name} {seed}: {run}");
        assert_eq!(run["collided"], false, "{name} {seed}");
        let error = run["target_error"].as_f64().unwrap();
        assert!(error < 1.5, "{name} {seed}: {error} mm off");
    }
}

/// In a world twice as rough as the steering is told (the campaign's "clinical x2, lab-told"),
/// the fixes disagree with the model throughout, and a stall there is not told from a lost tip:
/// this run, a 3.2 mm stall at 33 mm with the estimate 3.3 mm off, touched a sphere 6 mm later
/// when its stall was taken for held; it stops, reported, before it can.
#[test]
fn at_twice_the_world_a_stall_still_stops_before_a_sphere() {
    let paper = example("paper");
    let mut args: Vec<String> = [paper.to_str().unwrap(), "--closed-loop", "--runs", "1"]
        .map(String::from)
        .to_vec();
    args.insert(0, "simulate".into());
    args.extend(["--seed", "584", "--json", "--detail"].map(String::from));
    args.extend(twice_clinical_flags());
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let run = &needle_json(&args)["runs_detail"][0];
    assert_eq!(run["collided"], false, "{run}");
    assert_eq!(run["stop_reason"], "tracking_lost", "{run}");
}
