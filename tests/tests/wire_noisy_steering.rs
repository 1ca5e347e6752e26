//! Closed-loop steering on the device over a line that flips 1 % and drops 1 % of the bytes in
//! each direction. Long answers (the schedule, a replaced continuation) come in short parts, so
//! every insertion completes with the figures of the same insertion steered in-process; only
//! the count of repeated readings (the transport's) differs. In-process line (hil-sim's library,
//! no baud pacing), so it takes seconds.

mod wire_support;

use hil_sim::InProcess;
use needle_link::{Client, ClientConfig, LinkError, Transport};
use needle_sim::{closed_loop, in_process, Controller, Perturbation, Planned, TrackerFaults};
use planner_core::execute::schedule::schedule;
use planner_core::steer::{SteerConfig, SteerReply, SteerStats, TipMeasurement};
use planner_core::{plan, Scenario};
use std::time::Duration;
use wire_support::{noisy, Sim};

/// The device behind the link as the closed loop's controller.
struct OnDevice<'a, T: Transport>(&'a mut Client<T>);

impl<T: Transport> Controller for OnDevice<'_, T> {
    type Error = LinkError;
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, LinkError> {
        self.0.steer(m)
    }
    fn stats(&mut self) -> Result<SteerStats, LinkError> {
        self.0.steer_status().map(|(stats, _)| stats)
    }
}

#[test]
fn steering_over_a_noisy_line_gives_the_in_process_figures() {
    let s = Scenario::paper();
    let best = plan(&s).unwrap().best().unwrap().clone();
    let sched = schedule(&s, &best).unwrap();
    let planned = Planned::of(&s, &best);
    let config = SteerConfig::DEFAULT;
    let device = InProcess::with_lines(noisy(21), noisy(22)).audited();
    let link_config = ClientConfig {
        timeout: Duration::from_millis(100),
        retries: 400,
        deadline: None,
    };
    let mut client = Client::new(Sim(device), link_config);
    let result = client
        .plan(&s, &mut |_| {})
        .expect("a plan through the noise");
    assert_eq!(result.unwrap().planned.schedule, Some(Ok(sched.clone())));
    let p = Perturbation::default();
    let faults = TrackerFaults::default();
    let mut repeated = 0;
    for seed in 1..=3 {
        let steps = client.steer_start(&config).expect("steering starts");
        assert_eq!(steps, sched.steps);
        let on_device = closed_loop(
            &s,
            &planned,
            &sched,
            &p,
            &faults,
            &mut OnDevice(&mut client),
            seed,
        )
        .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let mut here = in_process(&s, &sched, &config).unwrap();
        let expected = closed_loop(&s, &planned, &sched, &p, &faults, &mut here, seed).unwrap();
        assert_eq!(
            on_device.run.target_error.to_bits(),
            expected.run.target_error.to_bits()
        );
        assert_eq!(on_device.stop_reason, expected.stop_reason);
        repeated += on_device.stats.repeated;
        let stats = SteerStats {
            repeated: expected.stats.repeated,
            ..on_device.stats
        };
        assert_eq!(stats, expected.stats, "seed {seed}");
    }
    let link = client.stats();
    let device = &client.link().0;
    let audit = device.audit_report();
    let (up, down) = device.line_stats();
    println!(
        "3 insertions: {repeated} readings repeated; host sent {} frames, retried {}, detected {} \
         damaged; line flipped {} / {} bytes, dropped {} / {}",
        link.sent, link.retried, link.detected, up.flipped, down.flipped, up.dropped, down.dropped
    );
    assert!(
        up.flipped > 100 && down.flipped > 100,
        "the line was not noisy"
    );
    assert!(repeated > 0, "no reading needed sending again");
    assert_eq!(audit.forged_to_device + audit.forged_to_host, 0);
}
