//! The firmware, built for QEMU's mps2-an386 (Cortex-M4F), answering `needle send` over its
//! emulated UART: its plans and the motor schedules it computes for them equal the host's bit
//! for bit, malformed frames and a scenario over capacity get their typed error replies, and it
//! keeps serving after them.

mod firmware_support;

use firmware_support::{build_firmware, emulator_ready, Qemu};
use needle_e2e::{example, needle, request_with_obstacles};
use needle_link::{open, Client, ClientConfig, LinkTarget};
use planner_core::wire::{encode_payload, Directed, Fault, ReplyBody, Request, ENCODE_SCRATCH};
use planner_core::PlanError;
use serde_json::Value;
use std::time::Duration;

fn without_stats(json: &str) -> Value {
    let mut v: Value = serde_json::from_str(json).expect("needle prints JSON");
    v.as_object_mut().expect("an object").remove("stats");
    v
}

fn run(args: &[&str]) -> String {
    let out = needle().args(args).output().expect("run needle");
    assert!(
        out.status.success(),
        "needle {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("UTF-8")
}

/// `needle send` through QEMU prints the plan `needle plan` prints, number for number (the JSON
/// numbers are the shortest decimal forms of the f32 values, so equal text is equal bits),
/// `best.schedule` included: the device's schedule (which `send` re-checks) is the host's.
fn assert_device_plan_equals_host(addr: &str, scenario: &str) {
    let file = example(scenario);
    let file = file.to_str().expect("UTF-8 path");
    let host = run(&["plan", file, "--json"]);
    let device = run(&["send", file, "--tcp", addr, "--json", "--timeout", "120"]);
    let (h, d) = (without_stats(&host), without_stats(&device));
    assert!(h["best"].is_object(), "{scenario}: the host found no plan");
    let steps = d["best"]["schedule"]["steps"].as_array();
    assert!(
        steps.is_some_and(|s| !s.is_empty()),
        "{scenario}: the device sent no schedule"
    );
    assert_eq!(
        h, d,
        "{scenario}: the device's plan differs from the host's"
    );
}

/// A frame whose CRC is right but whose payload is no message of the protocol.
fn undecodable_frame() -> Vec<u8> {
    let raw = [0xFF, 0xFF, 0xFF, 0x7F, 0x13];
    let mut frame = Vec::new();
    let mut scratch = [0u8; ENCODE_SCRATCH];
    let direction = <Request as Directed>::DIRECTION;
    encode_payload(direction, &raw, &mut scratch, &mut |b: &[u8]| {
        frame.extend_from_slice(b)
    })
    .expect("five bytes fit");
    frame
}

/// Waits for the fault answering a malformed frame.
fn expect_fault(client: &mut Client<Box<dyn needle_link::Transport>>, want: Fault) {
    loop {
        match client.next_reply().expect("link") {
            // A late duplicate answer to the previous session's last request (its client may
            // repeat a request the device then answers twice): stale, skipped as the client does.
            Some(r) if r.header.id != 0 && !matches!(r.body, ReplyBody::Fault(_)) => continue,
            Some(r) => break assert_eq!(r.body, ReplyBody::Fault(want)),
            None => panic!("no answer to a malformed frame (expected {want:?})"),
        }
    }
}

#[test]
fn firmware_in_qemu_plans_like_the_host_and_answers_bad_input() {
    if !emulator_ready("firmware_in_qemu_plans_like_the_host_and_answers_bad_input") {
        return;
    }
    let image = build_firmware("mps2-an386", "mps2-an386");
    let mut qemu = Qemu::start("mps2-an386", &image);

    assert_device_plan_equals_host(&qemu.addr, "paper");
    assert_device_plan_equals_host(&qemu.addr, "space");
    // The device's full capacity: 256 spheres, 32 of them near the path.
    assert_device_plan_equals_host(&qemu.addr, "spheres256");

    let config = ClientConfig {
        timeout: Duration::from_secs(10),
        retries: 2,
        deadline: None,
    };
    let link = open(&LinkTarget::Tcp(qemu.addr.clone())).expect("connect to QEMU");
    let mut client = Client::new(link, config);
    // A corrupted frame (valid stuffing, wrong CRC-32).
    client.send_raw(&[0, 7, 1, 2, 3, 4, 5, 6, 0]).unwrap();
    expect_fault(&mut client, Fault::BadCrc);
    // A frame with a good CRC that is not a message.
    client.send_raw(&undecodable_frame()).unwrap();
    expect_fault(&mut client, Fault::Undecodable);
    // A frame longer than any message.
    let mut long = vec![0u8];
    long.extend(std::iter::repeat_n(0x55, 2000));
    long.push(0);
    client.send_raw(&long).unwrap();
    expect_fault(&mut client, Fault::FrameTooLong);
    // A scenario over the planner's capacity: the typed planner error comes back.
    let over = planner_core::DEVICE_MAX_OBSTACLES + 1;
    let result = client
        .plan_encoded(&request_with_obstacles(over), &mut |_| {})
        .expect("the device answers an over-capacity scenario");
    assert_eq!(
        result.err(),
        Some(PlanError::TooManyObstacles {
            given: 257,
            capacity: 256
        })
    );
    // The same link still plans, and the plan is the host's, bit for bit.
    let paper = needle_scenario::load_scenario(&example("paper")).unwrap();
    let on_device = client
        .plan(&paper, &mut |_| {})
        .expect("plan after bad input");
    let host = planner_core::device::plan_as_device(&paper, None);
    assert_eq!(
        postcard::to_stdvec(&on_device).unwrap(),
        postcard::to_stdvec(&host).unwrap()
    );
    let schedule = on_device
        .unwrap()
        .planned
        .schedule
        .expect("the device's schedule");
    assert_eq!(
        postcard::to_stdvec(&schedule).unwrap(),
        postcard::to_stdvec(&host.unwrap().planned.schedule.unwrap()).unwrap(),
        "the device's schedule is the host's"
    );
    drop(client);

    // And `needle send` on a new connection is served too.
    assert_device_plan_equals_host(&qemu.addr, "paper");
    assert!(qemu.running(), "the firmware stopped QEMU (a fault)");
}
