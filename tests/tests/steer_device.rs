//! Closed-loop steering with the controller on a device: the firmware in QEMU and hil-sim over
//! a pty steer the simulated insertions exactly as the in-process controller does, bit for bit
//! (the JSON of `needle simulate --closed-loop --detail`, every point of every run).

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

fn assert_device_steers_like_the_host(device: &[&str], paper: &str, space: &str) {
    for (name, runs) in [("paper", paper), ("space", space)] {
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
    assert_device_steers_like_the_host(&["--port", &sim.address], "20", "5");
}

fn firmware_steers_like_the_host(test: &str, paper: &str, space: &str) {
    if !emulator_ready(test) {
        return;
    }
    let image = build_firmware("mps2-an386", "mps2-an386");
    let mut qemu = Qemu::start("mps2-an386", &image);
    assert_device_steers_like_the_host(&["--tcp", &qemu.addr], paper, space);
    assert!(qemu.running(), "the firmware stopped QEMU (a fault)");
}

/// The normal suite's share: each emulated reading costs about a million instructions, so 20 + 5
/// runs take minutes in QEMU; the full set is the ignored test below.
#[test]
fn the_firmware_in_qemu_steers_like_the_host() {
    firmware_steers_like_the_host("the_firmware_in_qemu_steers_like_the_host", "4", "1");
}

/// The long campaign: 20 paper and 5 space runs (`cargo test --release -p needle-e2e --test
/// steer_device -- --ignored`; 12.5 minutes on this machine with both cores shared).
#[test]
#[ignore]
fn the_firmware_in_qemu_steers_20_paper_and_5_space_runs_like_the_host() {
    firmware_steers_like_the_host(
        "the_firmware_in_qemu_steers_20_paper_and_5_space_runs_like_the_host",
        "20",
        "5",
    );
}
