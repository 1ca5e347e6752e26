//! 500 plan requests in a row over a line that flips 1% and drops 1% of the bytes in each
//! direction. Run in-process (hil-sim's library, the same device service, no baud pacing) so it
//! takes seconds: silence is detected at once instead of after a real timeout.
//!
//! Must hold: no damaged frame is ever accepted (audited in both directions), every request ends
//! with the exact plan or a clear error, the device keeps serving, nothing hangs.

mod wire_support;

use hil_sim::InProcess;
use needle_link::{Client, ClientConfig, LinkError};
use planner_core::device::plan_as_device;
use planner_core::Scenario;
use std::time::Duration;
use wire_support::{noisy, Sim};

const REQUESTS: usize = 500;

#[test]
fn five_hundred_plans_over_a_noisy_line() {
    let scenario = Scenario::paper();
    let expected = postcard::to_stdvec(&plan_as_device(&scenario, None)).unwrap();
    let device = InProcess::with_lines(noisy(11), noisy(12)).audited();
    let config = ClientConfig {
        timeout: Duration::from_millis(100),
        retries: 20,
        deadline: None,
    };
    let mut client = Client::new(Sim(device), config);
    let mut hello_ok = false;
    for _ in 0..20 {
        if client.hello().is_ok() {
            hello_ok = true;
            break;
        }
    }
    assert!(hello_ok, "no hello through the noise");
    let (mut exact, mut failed) = (0, 0);
    for i in 0..REQUESTS {
        match client.plan(&scenario, &mut |_| {}) {
            Ok(result) => {
                let got = postcard::to_stdvec(&result).unwrap();
                assert_eq!(got, expected, "request {i}: a different plan was accepted");
                exact += 1;
            }
            Err(e) => {
                // A clear error, and only of the kinds a bad line explains.
                assert!(
                    matches!(e, LinkError::NoAnswer { .. } | LinkError::CorruptResult),
                    "request {i}: {e}"
                );
                assert!(!e.to_string().is_empty());
                failed += 1;
            }
        }
    }
    let link = client.stats();
    let device = &client.link().0;
    let audit = device.audit_report();
    let (up, down) = device.line_stats();
    let dev = device.device_stats();
    println!(
        "{REQUESTS} plan requests: {exact} exact plans, {failed} failed with a clear error\n\
         host: sent {} frames, retried {}, detected {} damaged (timeouts {})\n\
         device: {} good frames, {} bad CRC, {} truncated, {} too long, {} undecodable, {} plans run\n\
         line: to device {} bytes ({} flipped, {} dropped), to host {} bytes ({} flipped, {} dropped)\n\
         audit: device accepted {} frames ({} never sent), host accepted {} ({} never sent)",
        link.sent,
        link.retried,
        link.detected,
        link.timeouts,
        dev.frames,
        dev.bad_crc,
        dev.truncated,
        dev.too_long,
        dev.undecodable,
        dev.plans,
        up.bytes,
        up.flipped,
        up.dropped,
        down.bytes,
        down.flipped,
        down.dropped,
        audit.accepted_by_device,
        audit.forged_to_device,
        audit.accepted_by_host,
        audit.forged_to_host,
    );
    assert_eq!(
        audit.forged_to_device, 0,
        "a damaged frame reached the device"
    );
    assert_eq!(audit.forged_to_host, 0, "a damaged frame reached the host");
    assert!(
        up.flipped > 100 && down.flipped > 100,
        "the line was not noisy"
    );
    assert!(link.retried > 0 && link.detected > 0);
    // Retries carry nearly every request through 2% byte damage.
    assert!(
        exact >= REQUESTS * 95 / 100,
        "only {exact} of {REQUESTS} exact"
    );
    // The device still serves: one more plan, now over a clean line.
    let mut clean = Client::new(Sim(InProcess::new()), config);
    assert_eq!(
        postcard::to_stdvec(&clean.plan(&scenario, &mut |_| {}).unwrap()).unwrap(),
        expected
    );
    assert!(client.ping().is_ok() || client.ping().is_ok());
}

/// Bytes on the wire for the paper scenario (printed for docs/protocol.md; asserted against
/// the frame bounds).
#[test]
fn wire_bytes_for_the_paper_scenario() {
    let scenario = Scenario::paper();
    let request = postcard::to_stdvec(&planner_core::wire::PlanRequest::new(&scenario)).unwrap();
    let result = postcard::to_stdvec(&plan_as_device(&scenario, None)).unwrap();
    let mut client = Client::new(Sim(InProcess::new()), ClientConfig::default());
    client.hello().unwrap();
    let before = client.stats();
    client.plan(&scenario, &mut |_| {}).unwrap().unwrap();
    let s = client.stats();
    println!(
        "paper scenario: plan request {} bytes encoded, plan result {} bytes encoded; \
         on the wire (frames, clean line): host to device {} bytes in {} frames, device to host {} bytes",
        request.len(),
        result.len(),
        s.bytes_out - before.bytes_out,
        s.sent - before.sent,
        s.bytes_in - before.bytes_in,
    );
    assert_eq!(s.retried, 0);
    let ram = std::mem::size_of::<planner_core::device::DeviceService>();
    println!(
        "frames: max payload {} bytes, max frame {} bytes with delimiters; upload buffer {}, \
         result buffer {}; DeviceService {} bytes of RAM (host layout)",
        planner_core::wire::MAX_PAYLOAD,
        planner_core::wire::MAX_WIRE_FRAME,
        planner_core::wire::MAX_PLAN_REQUEST,
        planner_core::wire::MAX_PLAN_RESULT,
        ram
    );
    // 32 KiB at the device's capacity of 256 spheres (30.1 KiB on the board, leaving its stack
    // room within the 60 KiB RAM budget); the host's layout holds every scenario at the host's
    // (each obstacle of it under 90 bytes: planner-core's device::tests), and the board's own
    // RAM is measured by `cargo xtask device-bench`.
    let extra = 90 * (planner_core::MAX_OBSTACLES - planner_core::DEVICE_MAX_OBSTACLES);
    assert!(
        ram < 32 * 1024 + extra,
        "the service must fit a small MCU's RAM"
    );
    assert!(request.len() <= planner_core::wire::MAX_PLAN_REQUEST);
    assert!(result.len() <= planner_core::wire::MAX_PLAN_RESULT);
}
