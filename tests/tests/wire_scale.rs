//! Scale on the wire: the device holds `DEVICE_MAX_OBSTACLES` (256) spheres. `needle send` to
//! hil-sim over TCP plans the scale bench's 256 spheres (examples/spheres256.toml, 32 near the path,
//! `planner.risk_within_mm`) as the host does, bit for bit, and a scenario the host holds but the
//! device does not (257 up to 512 spheres) gets the device's typed refusal, in hil-sim as on the
//! board.

mod wire_support;

use needle_analysis::scale::near_and_far;
use needle_e2e::{example, TempScenario};
use needle_link::{Client, ClientConfig};
use needle_scenario::load_scenario;
use needle_scenario::write::scenario_toml;
use planner_core::device::plan_as_device;
use planner_core::{PlanError, DEVICE_MAX_OBSTACLES, HOST_MAX_OBSTACLES};
use wire_support::{run_needle, Sim, SimProcess};

#[test]
fn the_example_is_the_bench_scenario() {
    let file = load_scenario(&example("spheres256")).unwrap();
    assert_eq!(file, near_and_far(1, 256, 32).all);
}

#[test]
fn send_plans_256_spheres_as_the_host_does_and_refuses_257() {
    assert_eq!(DEVICE_MAX_OBSTACLES, 256);
    let sim = SimProcess::start(&["--tcp", "127.0.0.1:0"]);
    let addr = sim.address.as_str();
    let all = example("spheres256");
    let file = all.to_str().unwrap();
    let (ok_l, out_l, err_l) = run_needle(&["plan", file, "--json"]);
    let send = ["send", file, "--tcp", addr, "--timeout", "120", "--json"];
    let (ok_r, out_r, err_r) = run_needle(&send);
    assert!(ok_l && ok_r, "{err_l} / {err_r}");
    let strip = |s: &str| s.split("\"stats\"").next().unwrap_or(s).to_string();
    assert_eq!(strip(&out_l), strip(&out_r));
    assert!(out_l.contains("\"best\":{"), "{out_l}");
    let over = near_and_far(1, DEVICE_MAX_OBSTACLES + 1, 32).all;
    let f = TempScenario::new(&scenario_toml(&over, "over", ""));
    let (ok, _, err) = run_needle(&["send", f.0.to_str().unwrap(), "--tcp", addr]);
    assert!(!ok, "{err}");
    let want = format!("257 obstacles but the device holds at most {DEVICE_MAX_OBSTACLES}");
    assert!(err.contains(&want), "{err}");
}

#[test]
fn the_device_refuses_what_only_the_host_holds() {
    let mut c = Client::new(Sim(hil_sim::InProcess::new()), ClientConfig::default());
    c.hello().expect("hello");
    for total in [DEVICE_MAX_OBSTACLES + 1, HOST_MAX_OBSTACLES] {
        let s = near_and_far(2, total, 32).all;
        let refused = Err(PlanError::TooManyObstacles {
            given: total as u16,
            capacity: DEVICE_MAX_OBSTACLES as u16,
        });
        // Sent when the wire carries it (the device refuses it), answered alike when not.
        assert_eq!(c.plan(&s, &mut |_| {}).expect("link"), refused);
        assert_eq!(plan_as_device(&s, None), refused);
        // The host plans it.
        assert!(planner_core::plan(&s).unwrap().best().is_some());
    }
}
