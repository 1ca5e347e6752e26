//! Hundreds of spheres: the host holds 512 and plans them, refuses 513 with the planner's typed
//! error, and `planner.risk_within_mm` is checked like the other planner keys.

use needle_cli::scale::near_and_far;
use needle_cli::scenario::write::scenario_toml;
use needle_e2e::{example, needle_fails_with, needle_json, TempScenario};

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
