//! The step timer's arithmetic: prescalers, the absolute schedule across the counter's wrap,
//! late interrupts caught up on, long waits in pieces, the clock and the encoders.

use super::*;
use crate::bench::bench_config;
use crate::{Controller, SafetyConfig};

fn event(ticks: u32, step: [bool; 2], dir: [i8; 2]) -> StepEvent {
    StepEvent { ticks, step, dir }
}

#[test]
fn the_prescaler_divides_the_clock_exactly_or_is_refused() {
    // An STM32F4's APB1 timers: 84 MHz behind the PLL, 16 MHz on the internal oscillator.
    assert_eq!(prescaler(84_000_000, 1_000_000), Ok(83));
    assert_eq!(prescaler(16_000_000, 1_000_000), Ok(15));
    assert_eq!(prescaler(1_000_000, 1_000_000), Ok(0));
    assert_eq!(prescaler(65_536_000, 1_000), Ok(u16::MAX));
    assert_eq!(prescaler(65_537_000, 1_000), Err(TimerError::Prescaler));
    assert_eq!(prescaler(84_000_000, 1_024_000), Err(TimerError::Prescaler));
    assert_eq!(prescaler(84_000_000, 0), Err(TimerError::TickRate));
    assert_eq!(prescaler(1_000_000, 2_000_000), Err(TimerError::TickRate));
}

#[test]
fn waits_in_ticks_round_up_and_allow_for_the_first_change() {
    // 2 µs at 1 MHz: two whole ticks, and the first change may come at once.
    assert_eq!(ticks_for_ns(2_000, 1_000_000), 3);
    assert_eq!(ticks_for_ns(1_001, 1_000_000), 3);
    assert_eq!(ticks_for_ns(650, 1_000_000), 2);
    assert_eq!(ticks_for_ns(0, 1_000_000), 1);
    assert_eq!(ticks_for_ns(u32::MAX, u32::MAX), u32::MAX);
}

#[test]
fn an_event_far_enough_is_armed_at_its_count_even_across_the_wrap() {
    let mut c = StepClock::IDLE;
    let start = u32::MAX - 10;
    c.start(start, event(100, [true, false], [1, 1]));
    assert!(c.is_running());
    assert_eq!(c.action(start + 2), Action::Arm(start.wrapping_add(100)));
    // The compare matches a tick late: fire, and the next event counts from the due count.
    assert_eq!(c.action(start.wrapping_add(101)), Action::Fire);
    assert_eq!(c.take(), Some(event(100, [true, false], [1, 1])));
    c.push(event(50, [false, true], [1, -1]));
    assert_eq!(
        c.action(start.wrapping_add(103)),
        Action::Arm(start.wrapping_add(150))
    );
}

#[test]
fn an_event_due_within_the_lead_is_waited_for_not_armed() {
    let mut c = StepClock::IDLE;
    c.start(1000, event(10, [true, true], [1, 1]));
    assert_eq!(c.action(1006), Action::Arm(1010));
    let mut c = StepClock::IDLE;
    c.start(1000, event(10, [true, true], [1, 1]));
    assert_eq!(c.action(1007), Action::Spin(1010));
    assert_eq!(c.action(1009), Action::Spin(1010));
    assert_eq!(c.action(1010), Action::Fire);
}

#[test]
fn a_late_interrupt_delays_one_step_and_the_train_keeps_its_times() {
    let mut c = StepClock::IDLE;
    c.start(0, event(100, [true, false], [1, 1]));
    // Served 150 ticks late: this step now, the next two at once (they are due too), then the
    // fourth at its own time: 100 + 20 + 20 + 200.
    assert_eq!(c.action(250), Action::Fire);
    c.take();
    c.push(event(20, [true, false], [1, 1]));
    assert_eq!(c.action(251), Action::Fire);
    c.take();
    c.push(event(20, [true, false], [1, 1]));
    assert_eq!(c.action(252), Action::Fire);
    c.take();
    c.push(event(200, [true, false], [1, 1]));
    assert_eq!(c.action(253), Action::Arm(340));
}

#[test]
fn a_long_wait_is_armed_in_pieces_shorter_than_half_the_counter() {
    let mut c = StepClock::IDLE;
    c.start(5, event(u32::MAX, [true, false], [1, 1]));
    assert_eq!(c.action(5), Action::Arm(5 + LONGEST_ARM));
    assert_eq!(c.action(5 + LONGEST_ARM), Action::Arm(5 + 2 * LONGEST_ARM));
    assert_eq!(
        c.action(5 + 2 * LONGEST_ARM),
        Action::Arm(5u32.wrapping_add(3 * LONGEST_ARM))
    );
    let last = 5u32.wrapping_add(3 * LONGEST_ARM);
    assert_eq!(c.action(last), Action::Arm(5u32.wrapping_add(u32::MAX)));
    assert_eq!(c.action(5u32.wrapping_add(u32::MAX)), Action::Fire);
}

#[test]
fn a_stopped_train_gives_nothing_more() {
    let mut c = StepClock::IDLE;
    c.start(0, event(10, [true, false], [1, 1]));
    c.stop();
    assert!(!c.is_running());
    assert_eq!(c.take(), None);
}

#[test]
fn a_direction_change_is_seen_only_on_the_axes_that_step() {
    let mut c = StepClock::IDLE;
    assert!(c.dir_changes(&event(1, [true, false], [1, -1])));
    assert!(!c.dir_changes(&event(1, [true, false], [1, 1])));
    // The rotation's first step sets its direction; a later reversal is a change.
    assert!(c.dir_changes(&event(1, [false, true], [1, 1])));
    assert!(!c.dir_changes(&event(1, [true, true], [1, 1])));
    assert!(c.dir_changes(&event(1, [false, true], [1, -1])));
}

#[test]
fn counts_are_reached_within_half_the_range() {
    assert!(reached(10, 10));
    assert!(reached(11, 10));
    assert!(!reached(9, 10));
    assert!(reached(3, u32::MAX - 3));
    assert!(!reached(u32::MAX - 3, 3));
}

#[test]
fn milliseconds_are_exact_over_the_counters_wrap_at_any_rate() {
    let mut m = Millis::new(u32::MAX - 499);
    assert_eq!(m.at(u32::MAX, 1_000_000), 0);
    assert_eq!(m.at(499, 1_000_000), 0);
    assert_eq!(m.at(500, 1_000_000), 1);
    // A rate that is no whole number of ticks a millisecond: 3 ms are 3 · 1.5 ticks.
    let mut m = Millis::new(0);
    assert_eq!(m.at(1, 1500), 0);
    assert_eq!(m.at(2, 1500), 1);
    assert_eq!(m.at(4, 1500), 2);
    assert_eq!(m.at(5, 1500), 3);
    let mut total = 0;
    let mut m = Millis::new(7);
    for k in 1..=1000u32 {
        total = m.at(7 + k * 977, 1_000_000);
    }
    assert_eq!(total, 977);
}

#[test]
fn a_16_bit_encoder_counts_on_through_its_wraps_both_ways() {
    let mut e = EncoderCount::new(65_530);
    assert_eq!(e.at(4), 10);
    assert_eq!(e.at(30_000), 30_006);
    assert_eq!(e.at(60_000), 60_006);
    assert_eq!(e.at(10), 65_552);
    let mut e = EncoderCount::new(3);
    assert_eq!(e.at(65_535), -4);
    assert_eq!(e.at(40_000), -25_539);
}

#[test]
fn encoder_counts_become_the_nearest_motor_step() {
    // A 1000-line encoder (4000 counts a turn) on a motor of 3200 steps a turn.
    assert_eq!(encoder_steps(4000, 3200, 4000), Some(3200));
    assert_eq!(encoder_steps(1, 3200, 4000), Some(1));
    assert_eq!(encoder_steps(-1, 3200, 4000), Some(-1));
    assert_eq!(encoder_steps(5, 2, 4), Some(3));
    assert_eq!(encoder_steps(-5, 2, 4), Some(-3));
    assert_eq!(encoder_steps(i32::MAX, 4, 1), Some(i32::MAX));
    assert_eq!(encoder_steps(i32::MIN, 4, 1), Some(i32::MIN));
    assert_eq!(encoder_steps(10, 3200, 0), None);
}

/// The bench's homing driven through the clock as the interrupt drives it, the compare firing
/// late by up to 7 ticks: the steps are given at their due counts plus that lateness, never
/// early, and the train is the controller's own.
#[test]
fn the_clock_gives_the_controllers_train_at_its_times() {
    let mut reference = Controller::new(bench_config(), SafetyConfig::BENCH).unwrap();
    let mut core = reference.clone();
    for c in [&mut reference, &mut core] {
        c.arm().unwrap();
        c.home().unwrap();
    }
    let mut clock = StepClock::IDLE;
    let mut now = 0xFFFF_0000u32;
    clock.start(now, core.next_step().unwrap());
    let mut due = now;
    let mut given = 0u32;
    while given < 20_000 {
        match clock.action(now) {
            Action::Arm(at) => now = at.wrapping_add(given % 8),
            Action::Spin(at) => now = at,
            Action::Fire => {
                let e = clock.take().unwrap();
                assert_eq!(Some(e), reference.next_step());
                due = due.wrapping_add(e.ticks);
                assert!(reached(now, due) && now.wrapping_sub(due) < 8 + MIN_LEAD);
                given += 1;
                let Some(next) = core.next_step() else { break };
                clock.push(next);
                now = now.wrapping_add(1);
            }
        }
    }
    assert_eq!(given, 20_000);
    // The controller is one event ahead: the one pending.
    assert_eq!(clock.take(), reference.next_step());
    assert_eq!(core.steps(), reference.steps());
}
