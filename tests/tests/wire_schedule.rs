//! The device computes the motor schedule: the in-process hil-sim device (the same
//! `DeviceService` as the firmware) returns, for every example and for a schedule with bevel
//! turns, the schedule the host builds from the same report, bit for bit, and it passes the
//! nominal re-check `needle send` applies.

mod wire_support;

use hil_sim::InProcess;
use needle_device::verify::verified_schedule;
use needle_e2e::example;
use needle_link::{Client, ClientConfig};
use planner_core::execute::nominal::check;
use planner_core::execute::schedule::{schedule, Op};
use planner_core::{plan_scheduled, Form, FormSet, Scenario};
use wire_support::Sim;

fn load(name: &str) -> Scenario {
    needle_scenario::load_scenario(&example(name)).expect("example scenario")
}

/// Plans on the device and checks its schedule against the host's, bit for bit.
fn assert_device_schedule_is_the_hosts(client: &mut Client<Sim>, scenario: &Scenario) -> usize {
    let on_device = client
        .plan(scenario, &mut |_| {})
        .expect("link")
        .expect("a plan");
    assert!(on_device.chance.is_none());
    let on_device = on_device.planned;
    let device = on_device
        .schedule
        .as_ref()
        .expect("a best form's schedule")
        .as_ref()
        .expect("a schedule");
    let best = on_device.report.best().expect("a best form");
    let host = schedule(scenario, best).expect("the host's schedule");
    assert_eq!(
        postcard::to_stdvec(device).unwrap(),
        postcard::to_stdvec(&host).unwrap(),
        "the device's schedule differs from the host's"
    );
    // The whole answer, report and schedule, is what the host computes for the scenario.
    assert_eq!(
        postcard::to_stdvec(&on_device).unwrap(),
        postcard::to_stdvec(&plan_scheduled(scenario).unwrap()).unwrap()
    );
    assert!(check(scenario, device).feasible);
    assert_eq!(verified_schedule(scenario, &on_device).unwrap(), device);
    device.steps.len()
}

#[test]
fn the_device_sends_the_hosts_schedule_bit_for_bit() {
    let mut client = Client::new(Sim(InProcess::new()), ClientConfig::default());
    client.hello().expect("hello");
    assert_eq!(
        assert_device_schedule_is_the_hosts(&mut client, &load("paper")),
        2
    );
    // Planned for steering as shipped: one duty-cycled arc kept clear of the spheres.
    assert!(assert_device_schedule_is_the_hosts(&mut client, &load("space")) >= 1);
    // A form with bevel turns between segments: rotate steps too.
    let mut lrr = load("paper");
    let mut only = FormSet::default();
    only.insert(Form::parse("LRR").unwrap());
    lrr.options.forms = only;
    assert_eq!(assert_device_schedule_is_the_hosts(&mut client, &lrr), 5);
    let on_device = client.plan(&lrr, &mut |_| {}).unwrap().unwrap();
    let ops = on_device.planned.schedule.unwrap().unwrap().steps;
    assert!(ops.iter().any(|s| matches!(s.op, Op::Rotate { .. })));
    // A slower driver changes the device's durations exactly as the host's.
    let mut slow = load("paper");
    slow.driver.insert_speed = 0.5;
    slow.driver.spin_rate = 1.5;
    assert_device_schedule_is_the_hosts(&mut client, &slow);
}
