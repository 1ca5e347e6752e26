//! Every transition of the safety state machine, on the simulated plant.

use crate::testbench::Bench;
use crate::{FaultCause, Inputs, MotionError, Move, State};

const PUSH: [Move; 1] = [Move::Insert { length_mm: 20.0 }];

#[test]
fn power_up_is_disarmed_and_nothing_moves_before_arming_and_homing() {
    let mut b = Bench::new();
    assert_eq!(b.c.state(), State::Disarmed);
    assert_eq!(
        b.c.execute(&PUSH),
        Err(MotionError::NotAllowed(State::Disarmed))
    );
    assert_eq!(b.c.home(), Err(MotionError::NotAllowed(State::Disarmed)));
    assert_eq!(b.drive(10), 0);
    b.c.arm().unwrap();
    assert_eq!(b.c.execute(&PUSH), Err(MotionError::NotHomed));
    assert_eq!(b.drive(10), 0);
    assert_eq!(b.p.actual(), [8000, 0]);
}

#[test]
fn homing_stops_at_the_switch_and_zeroes_both_axes() {
    let b = Bench::homed();
    assert!(b.c.status().homed);
    assert_eq!(b.c.steps(), [0, 0]);
    // The switch closes at the stage's 0: the controller's zero is there.
    assert_eq!(b.p.actual(), [0, 0]);
    assert_eq!(b.p.missed(), [0, 0]);
}

#[test]
fn homing_without_a_switch_in_the_travel_faults() {
    let cfg = crate::testbench::config();
    let mut plant = crate::testbench::plant_config(&cfg);
    plant.start = [200 * 1600, 0];
    plant.end = i32::MAX;
    let mut b = Bench::with(cfg, plant);
    b.c.arm().unwrap();
    b.c.home().unwrap();
    b.drive(usize::MAX);
    assert_eq!(b.c.state(), State::Faulted);
    let f = b.c.status().last_fault.unwrap();
    assert_eq!(f.cause, FaultCause::HomingFailed);
    assert_eq!(f.steps[0], -160 * 1600);
}

#[test]
fn a_schedule_runs_to_its_end_and_leaves_the_controller_armed() {
    let mut b = Bench::homed();
    b.c.execute(&[
        Move::Rotate { angle_deg: -45.0 },
        Move::InsertSpin {
            length_mm: 3.0,
            turns: 4,
        },
        Move::InsertDuty {
            length_mm: 2.0,
            duty: 0.5,
        },
    ])
    .unwrap();
    assert_eq!(b.c.state(), State::Moving);
    b.drive(usize::MAX);
    assert_eq!(b.c.state(), State::Armed);
    assert_eq!(b.c.steps(), [8000, -400]);
    b.p.wait_ms(100);
    assert_eq!(b.p.actual(), [8000, -400]);
    assert_eq!(b.p.missed(), [0, 0]);
    assert_eq!(b.c.status().speed, [0.0, 0.0]);
}

#[test]
fn estop_during_insertion_stops_both_axes_at_once_and_latches() {
    let mut b = Bench::homed();
    b.c.execute(&[Move::InsertSpin {
        length_mm: 10.0,
        turns: 8,
    }])
    .unwrap();
    b.drive(3000);
    let at = b.c.steps();
    assert!(at[0] > 0 && at[1] != 0, "{at:?}");
    b.p.estop = true;
    let inputs = b.p.inputs();
    let fault = b.c.update(b.p.now_ms(), &inputs).unwrap();
    assert_eq!(fault.cause, FaultCause::EStop);
    assert_eq!(fault.steps, at);
    // Not one step more, on either axis.
    assert_eq!(b.c.next_step(), None);
    assert_eq!(b.c.steps(), at);
    assert_eq!(b.c.status().speed, [0.0, 0.0]);
    // Latched: no request moves it, a reset keeps it.
    assert_eq!(b.c.arm(), Err(MotionError::Faulted(FaultCause::EStop)));
    assert_eq!(b.c.reset(), Err(MotionError::Faulted(FaultCause::EStop)));
    assert_eq!(b.c.home(), Err(MotionError::Faulted(FaultCause::EStop)));
    assert_eq!(b.c.state(), State::Faulted);
    // Cleared only once released; then disarmed and unhomed.
    let pressed = b.p.inputs();
    assert_eq!(
        b.c.clear_fault(&pressed),
        Err(MotionError::CauseActive(FaultCause::EStop))
    );
    b.p.estop = false;
    b.c.clear_fault(&b.p.inputs()).unwrap();
    assert_eq!(b.c.state(), State::Disarmed);
    assert!(!b.c.status().homed);
    assert_eq!(b.c.status().last_fault.unwrap().cause, FaultCause::EStop);
}

#[test]
fn the_estop_interrupt_stops_without_waiting_for_the_inputs() {
    let mut b = Bench::homed();
    b.c.execute(&PUSH).unwrap();
    b.drive(100);
    assert_eq!(b.c.estop().cause, FaultCause::EStop);
    assert_eq!(b.c.next_step(), None);
    // A second press reports the latched fault.
    assert_eq!(b.c.estop().steps, b.c.steps());
}

#[test]
fn the_far_limit_switch_stops_both_axes_and_latches_until_released() {
    let cfg = crate::testbench::config();
    let mut plant = crate::testbench::plant_config(&cfg);
    plant.end = 5 * 1600;
    plant.start = [1600, 0];
    let mut b = Bench::with(cfg, plant);
    b.c.arm().unwrap();
    b.c.home().unwrap();
    b.drive(usize::MAX);
    b.c.execute(&PUSH).unwrap();
    b.drive(usize::MAX);
    let f = b.c.status().last_fault.unwrap();
    assert_eq!(
        (b.c.state(), f.cause),
        (State::Faulted, FaultCause::LimitSwitch)
    );
    assert_eq!(f.steps[0], 5 * 1600);
    assert_eq!(f.position[0], 5.0);
    let closed = b.p.inputs();
    assert!(closed.limit);
    assert_eq!(
        b.c.clear_fault(&closed),
        Err(MotionError::CauseActive(FaultCause::LimitSwitch))
    );
    b.c.clear_fault(&Inputs::default()).unwrap();
    assert_eq!(b.c.state(), State::Disarmed);
}

#[test]
fn the_home_switch_met_while_retracting_faults() {
    let mut b = Bench::homed();
    b.c.execute(&[Move::Insert { length_mm: 1.0 }]).unwrap();
    b.drive(usize::MAX);
    // The stage slipped 2 mm back unseen (no encoder): retracting 1 mm meets the switch.
    let cfg = crate::testbench::config();
    let mut plant = crate::testbench::plant_config(&cfg);
    plant.start = [-1600, 0];
    plant.axes[0].encoder_steps = None;
    b.p = crate::plant::Plant::new(plant);
    b.c.arm().unwrap();
    b.c.execute(&[Move::Insert { length_mm: -1.0 }]).unwrap();
    b.drive(usize::MAX);
    assert_eq!(
        b.c.status().last_fault.unwrap().cause,
        FaultCause::HomeSwitch
    );
}

#[test]
fn a_stage_that_cannot_follow_gives_a_following_error() {
    let cfg = crate::testbench::config();
    let mut plant = crate::testbench::plant_config(&cfg);
    // A motor whose torque is gone under the insertion speed (above homing's): it slips.
    plant.axes[0].pull_out = 0.9 * 2.5 * 1600.0;
    let mut b = Bench::with(cfg, plant);
    b.c.arm().unwrap();
    b.c.home().unwrap();
    b.drive(usize::MAX);
    b.c.execute(&[Move::Insert { length_mm: 10.0 }]).unwrap();
    b.drive(usize::MAX);
    let f = b.c.status().last_fault.unwrap();
    assert_eq!(f.cause, FaultCause::FollowingError(crate::Axis::Insertion));
    assert!(b.p.missed()[0] > 0);
    let (commanded, read) = (f.steps[0], f.encoder[0].unwrap());
    assert!(commanded - read > 800, "{commanded} {read}");
}

#[test]
fn the_link_watchdog_holds_then_stops() {
    let mut b = Bench::homed();
    b.c.execute(&PUSH).unwrap();
    b.drive(2000);
    b.host = false;
    // The host's last word.
    b.c.heartbeat();
    let silent_from = b.p.now_ms();
    // Past the hold time: decelerating to rest, the moves kept.
    while b.c.state() == State::Moving {
        assert!(b.drive(1) == 1);
    }
    assert_eq!(b.c.state(), State::Holding);
    assert!(b.p.now_ms() - silent_from >= 200);
    b.drive(usize::MAX);
    let rest = b.c.steps();
    assert!(rest[0] < 20 * 1600);
    // Silent on: held at rest up to the stop time, then the link is lost.
    b.p.wait_ms(silent_from + 999 - b.p.now_ms());
    let inputs = b.p.inputs();
    assert_eq!(b.c.update(b.p.now_ms(), &inputs), None);
    assert_eq!(b.c.state(), State::Holding);
    b.p.wait_ms(1);
    let f = b.c.update(b.p.now_ms(), &inputs).unwrap();
    assert_eq!((f.cause, f.steps), (FaultCause::LinkLost, rest));
    // The axes stopped under control: homing is kept once cleared.
    b.c.clear_fault(&inputs).unwrap();
    assert!(b.c.status().homed);
}

#[test]
fn a_hold_resumes_to_the_same_end() {
    let mut b = Bench::homed();
    b.c.execute(&[
        Move::InsertSpin {
            length_mm: 4.0,
            turns: 2,
        },
        Move::Rotate { angle_deg: 30.0 },
    ])
    .unwrap();
    b.drive(1500);
    b.c.hold().unwrap();
    assert_eq!(b.c.resume(), Err(MotionError::NotAllowed(State::Holding)));
    b.drive(usize::MAX);
    assert_eq!(b.c.state(), State::Holding);
    b.c.resume().unwrap();
    b.drive(usize::MAX);
    assert_eq!(b.c.state(), State::Armed);
    assert_eq!(
        b.c.steps(),
        [6400, b.c.config().to_steps(crate::Axis::Rotation, 30.0)]
    );
    assert_eq!(b.p.missed(), [0, 0]);
}

#[test]
fn stop_decelerates_and_drops_the_moves() {
    let mut b = Bench::homed();
    b.c.execute(&[PUSH[0], Move::Rotate { angle_deg: 90.0 }])
        .unwrap();
    b.drive(3000);
    b.c.stop().unwrap();
    let n = b.drive(usize::MAX);
    assert!(n > 0 && n < 3000, "{n}");
    assert_eq!(b.c.state(), State::Armed);
    assert_eq!(b.c.steps()[1], 0);
    assert_eq!(b.c.status().moves_left, 0);
    assert_eq!(b.p.missed(), [0, 0]);
}

#[test]
fn disarm_and_reset_stop_at_once_and_reset_unhomes() {
    let mut b = Bench::homed();
    b.c.execute(&PUSH).unwrap();
    b.drive(100);
    b.c.disarm().unwrap();
    assert_eq!(b.c.next_step(), None);
    assert!(b.c.status().homed);
    b.c.reset().unwrap();
    assert!(!b.c.status().homed);
    assert_eq!(b.c.state(), State::Disarmed);
}

#[test]
fn soft_limits_refuse_the_whole_schedule() {
    let mut b = Bench::homed();
    let past = [
        Move::Insert { length_mm: 100.0 },
        Move::Insert { length_mm: 60.0 },
    ];
    assert_eq!(
        b.c.execute(&past),
        Err(MotionError::SoftLimit(crate::Axis::Insertion))
    );
    let back = [Move::Insert { length_mm: -0.1 }];
    assert_eq!(
        b.c.execute(&back),
        Err(MotionError::SoftLimit(crate::Axis::Insertion))
    );
    let twist = [
        Move::Rotate { angle_deg: 180.0 },
        Move::Rotate { angle_deg: 181.0 },
    ];
    assert_eq!(
        b.c.execute(&twist),
        Err(MotionError::SoftLimit(crate::Axis::Rotation))
    );
    // A spin from +90 degrees turns towards zero, within the limit; from +360 too.
    let spin = [
        Move::Rotate { angle_deg: 360.0 },
        Move::InsertSpin {
            length_mm: 1.0,
            turns: 2,
        },
    ];
    b.c.execute(&spin).unwrap();
    b.drive(usize::MAX);
    assert_eq!(b.c.steps(), [1600, 3200]);
    let bad = [Move::InsertDuty {
        length_mm: 1.0,
        duty: 1.5,
    }];
    assert_eq!(b.c.execute(&bad), Err(MotionError::BadMove));
    let nan = [Move::Insert {
        length_mm: f32::NAN,
    }];
    assert_eq!(b.c.execute(&nan), Err(MotionError::BadMove));
    assert_eq!(b.c.status().moves_left, 0);
}

#[test]
fn a_job_sets_rates_and_limits_at_rest_only() {
    let mut b = Bench::homed();
    let rates = crate::Rates {
        insert_mm_s: 1.0,
        rotate_deg_s: 90.0,
        spin_rev_s: 2.0,
    };
    b.c.set_job(rates, 10.0, 720.0).unwrap();
    assert_eq!(b.c.config().axes[0].max, 10.0);
    assert_eq!(b.c.config().axes[1].min, -720.0);
    assert_eq!(
        b.c.execute(&PUSH),
        Err(MotionError::SoftLimit(crate::Axis::Insertion))
    );
    assert_eq!(
        b.c.set_job(rates, f32::NAN, 720.0),
        Err(MotionError::Config(crate::ConfigField::SoftLimits(
            crate::Axis::Insertion
        )))
    );
    b.c.execute(&[Move::Insert { length_mm: 5.0 }]).unwrap();
    assert_eq!(
        b.c.set_job(rates, 20.0, 720.0),
        Err(MotionError::NotAllowed(State::Moving))
    );
}
