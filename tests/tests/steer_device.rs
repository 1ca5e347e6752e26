//! Closed-loop steering with the controller on a device: the firmware in QEMU and hil-sim over
//! a pty steer the simulated insertions exactly as the in-process controller does, bit for bit
//! (the JSON of `needle simulate --closed-loop --detail`, every point of every run), the plan of
//! `examples/paper-bounded.toml` made on the device under its collision bound.

mod firmware_support;
mod wire_support;

use firmware_support::{build_firmware, emulator_ready, Qemu};
use needle_e2e::{example, needle};
use wire_support::SimProcess;

/// The JSON without the counts of repeated readings, which on a device include the link's
/// resends of a reading whose answer was late (answered again, not applied: the rest is equal).
fn without_repeats(json: &[u8]) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(json).expect("JSON");
    v["summary"]["repeated"] = serde_json::Value::Null;
    for r in v["runs_detail"].as_array_mut().expect("runs") {
        r["steering"]["repeated"] = serde_json::Value::Null;
    }
    v
}

fn simulate(file: &str, runs: &str, device: &[&str]) -> Vec<u8> {
    let out = needle()
        .args([
            "simulate",
            file,
            "--runs",
            runs,
            "--seed",
            "3",
            "--closed-loop",
        ])
        .args(["--json", "--detail", "--timeout", "60"])
        .args(device)
        .output()
        .expect("run needle");
    assert!(
        out.status.success(),
        "needle simulate {device:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

fn assert_device_steers_like_the_host(device: &[&str], runs: &[(&str, &str)]) {
    for &(name, runs) in runs {
        let file = example(name);
        let file = file.to_str().unwrap();
        let host = simulate(file, runs, &[]);
        let on_device = simulate(file, runs, device);
        let v: serde_json::Value = serde_json::from_slice(&host).unwrap();
        assert!(
            v["summary"]["replans"].as_u64().unwrap() > 20,
            "{name}: no replans"
        );
        // Numbers print identically only when they are the same f32 values: equal JSON is
        // equal bits.
        assert!(
            without_repeats(&host) == without_repeats(&on_device),
            "{name}: the device steered differently from the in-process controller"
        );
    }
}

#[test]
fn hil_sim_over_a_pty_steers_like_the_host() {
    let sim = SimProcess::start(&[]);
    assert!(sim.address.starts_with("/dev/"), "{}", sim.address);
    let runs = [("paper", "20"), ("space", "5"), ("paper-bounded", "5")];
    assert_device_steers_like_the_host(&["--port", &sim.address], &runs);
}

fn firmware_steers_like_the_host(test: &str, runs: &[(&str, &str)]) {
    if !emulator_ready(test) {
        return;
    }
    let image = build_firmware("mps2-an386", "mps2-an386");
    let mut qemu = Qemu::start("mps2-an386", &image);
    assert_device_steers_like_the_host(&["--tcp", &qemu.addr], runs);
    assert!(qemu.running(), "the firmware stopped QEMU (a fault)");
}

/// The normal suite's share: each emulated reading costs about a million instructions, so 20 + 5
/// runs take minutes in QEMU; the full set is the ignored test below. The bounded paper plan is
/// made on the firmware under its 1 % bound before it is steered.
#[test]
fn the_firmware_in_qemu_steers_like_the_host() {
    firmware_steers_like_the_host(
        "the_firmware_in_qemu_steers_like_the_host",
        &[("paper", "2"), ("space", "1"), ("paper-bounded", "2")],
    );
}

/// The long campaign: 20 paper and 5 space runs (`cargo test --release -p needle-e2e --test
/// steer_device -- --ignored`; 12.5 minutes on this machine with both cores shared).
#[test]
#[ignore]
fn the_firmware_in_qemu_steers_20_paper_and_5_space_runs_like_the_host() {
    firmware_steers_like_the_host(
        "the_firmware_in_qemu_steers_20_paper_and_5_space_runs_like_the_host",
        &[("paper", "20"), ("space", "5"), ("paper-bounded", "5")],
    );
}
