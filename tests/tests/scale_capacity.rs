//! Hundreds of spheres: the host holds 512 and plans them, refuses 513 with the planner's typed
//! error, and `planner.risk_within_mm` is checked like the other planner keys.

use needle_analysis::scale::near_and_far;
use needle_e2e::{example, needle_fails_with, needle_json, TempScenario};
use needle_scenario::write::scenario_toml;

fn with_512() -> String {
    let s = near_and_far(5, planner_core::HOST_MAX_OBSTACLES, 32).all;
    assert_eq!(s.obstacles.len(), 512);
    scenario_toml(
        &s,
        "capacity",
        "# 512 spheres, 32 within 20 mm of the path\n",
    )
}

#[test]
fn the_host_plans_512_spheres_and_refuses_513() {
    let text = with_512();
    let f = TempScenario::new(&text);
    let v = needle_json(&["plan", &f.0.to_string_lossy(), "--json"]);
    assert!(v["best"]["form"].is_string(), "{v}");
    assert_eq!(v["best"]["feasible"], true, "{v}");
    let over = format!("{text}\n[[obstacles]]\ncenter = [0.0, 300.0, 0.0]\nradius = 1.0\n");
    needle_fails_with(
        &over,
        &["plan", "{}"],
        "513 obstacles given but the planner holds at most 512",
    );
}

#[test]
fn a_reach_out_of_range_is_refused_with_its_key() {
    let paper = std::fs::read_to_string(example("paper")).unwrap();
    for bad in ["0", "-3", "1001", "nan"] {
        let text = paper.replace(
            "[planner]\n",
            &format!("[planner]\nrisk_within_mm = {bad}\n"),
        );
        needle_fails_with(&text, &["plan", "{}"], "planner.risk_within_mm");
    }
    // Not above the clearance floor.
    let text = paper.replace(
        "[planner]\n",
        "[planner]\nmin_clearance = 2.0\nrisk_within_mm = 2.005\n",
    );
    needle_fails_with(
        &text,
        &["plan", "{}"],
        "at least planner.min_clearance + 0.01 mm",
    );
}

/// `needle bench --near-and-far`: the far spheres leave the plan as it was (checked by the
/// command, which fails otherwise) and both medians are printed, with the check's, the risk
/// spread's and the prediction's times culled, over every sphere and for the near alone (the
/// command fails unless culled and exhaustive agree); a bad spec or a total over the host's
/// capacity is a clear error.
#[test]
fn the_bench_times_many_spheres_beside_the_near_ones() {
    let v = needle_json(&["bench", "--near-and-far", "64,8", "--runs", "1", "--json"]);
    assert_eq!(
        (v["spheres"].as_u64(), v["near"].as_u64()),
        (Some(64), Some(8))
    );
    let ratio = v["ratio"].as_f64().unwrap();
    let (all, near) = (
        v["all_ms"].as_f64().unwrap(),
        v["near_ms"].as_f64().unwrap(),
    );
    assert!(
        all > 0.0 && near > 0.0 && (ratio - all / near).abs() < 1e-9,
        "{v}"
    );
    assert!(v["measured_forms"].as_u64().unwrap() >= 1, "{v}");
    for key in ["check_us", "risk_us", "predict_us"] {
        for part in ["culled", "every", "near"] {
            assert!(v[key][part].as_f64().unwrap() > 0.0, "{key}.{part}: {v}");
        }
    }
    for (spec, says) in [
        ("64", "expected TOTAL,NEAR"),
        ("8,64", "NEAR from 1 to TOTAL"),
        ("513,8", "TOTAL at most 512"),
    ] {
        let out = needle_e2e::needle()
            .args(["bench", "--near-and-far", spec, "--runs", "1"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(says), "{spec}: {err}");
    }
}
