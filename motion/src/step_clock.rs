//! A board's step timer in integers: the arithmetic between the controller's step train and a
//! free-running hardware counter, kept here so the host tests it (the firmware has no tests).
//!
//! The board counts ticks at [`MotionConfig::tick_hz`](crate::MotionConfig) on a 32-bit counter
//! that never stops, and sets a compare register to the count at which the next step is due.
//! [`StepClock`] keeps that schedule absolute: each event is due `ticks` after the one before,
//! not after the interrupt that drew it, so an interrupt served late (another interrupt, a
//! critical section) delays that one step and is caught up on, never carried into the train.
//! Beside it: the prescaler that makes the tick from the timer's clock, pulse and set-up times
//! in whole ticks, the milliseconds the controller's clock counts, and the encoders' 16-bit
//! counters widened and turned into motor steps.

use crate::StepEvent;

/// Fewest ticks between arming the compare and its match: below it, a compare written as the
/// counter passes it could be missed (and then not match for a whole wrap of the counter), so
/// the interrupt waits for the count itself.
pub const MIN_LEAD: u32 = 4;

/// Longest wait one compare covers: a wait longer than half the counter's range could not be
/// told from a count already passed, so it is covered by several.
pub const LONGEST_ARM: u32 = 1 << 30;

/// Why a timer cannot give the tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TimerError {
    /// The tick rate is zero or above the timer's clock.
    TickRate,
    /// The timer's clock is not a whole multiple of the tick rate, or needs a divider above
    /// the 16-bit prescaler's 65 536.
    Prescaler,
}

/// The prescaler register value (the clock is divided by it plus one) that turns a timer clock
/// of `timer_hz` into ticks of exactly `tick_hz`: a tick rate the clock does not divide would
/// stretch every interval of the train.
pub fn prescaler(timer_hz: u32, tick_hz: u32) -> Result<u16, TimerError> {
    if tick_hz == 0 || tick_hz > timer_hz {
        return Err(TimerError::TickRate);
    }
    if !timer_hz.is_multiple_of(tick_hz) {
        return Err(TimerError::Prescaler);
    }
    u16::try_from(timer_hz / tick_hz - 1).map_err(|_| TimerError::Prescaler)
}

/// Counter changes to wait for at least `ns` nanoseconds at `tick_hz`: the time rounded up to
/// whole ticks, and one more, since the first change can come at once.
pub fn ticks_for_ns(ns: u32, tick_hz: u32) -> u32 {
    let ticks = (u64::from(ns) * u64::from(tick_hz)).div_ceil(1_000_000_000);
    u32::try_from(ticks + 1).unwrap_or(u32::MAX)
}

/// What the step interrupt does next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Set the compare to this count and return: the event (or a waypoint of a long wait) is
    /// at least [`MIN_LEAD`] ticks away.
    Arm(u32),
    /// The event is due within [`MIN_LEAD`] ticks: wait for the counter to reach this count,
    /// then ask again.
    Spin(u32),
    /// The event is due (or late): give its step now.
    Fire,
}

/// The absolute schedule of one step train on a free-running counter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepClock {
    /// The count from which `remaining` runs: the last event's due count, or a later count
    /// on the way to a long wait's end.
    base: u32,
    /// Ticks from `base` to the pending event.
    remaining: u32,
    /// The event drawn but not yet given.
    pending: Option<StepEvent>,
    /// The direction each axis' DIR output was last given (0: never).
    dir: [i8; 2],
}

impl StepClock {
    /// No train: no event pending, the directions unknown.
    pub const IDLE: StepClock = StepClock {
        base: 0,
        remaining: 0,
        pending: None,
        dir: [0; 2],
    };

    /// Whether an event is pending (the timer is stepping).
    pub fn is_running(&self) -> bool {
        self.pending.is_some()
    }

    /// Starts a train at count `now` with its first event.
    pub fn start(&mut self, now: u32, first: StepEvent) {
        self.base = now;
        self.remaining = first.ticks;
        self.pending = Some(first);
    }

    /// Queues `next`, due `next.ticks` after the event just given (not after now).
    pub fn push(&mut self, next: StepEvent) {
        self.remaining = next.ticks;
        self.pending = Some(next);
    }

    /// Drops the pending event: the train is over (at rest, or stopped by a fault).
    pub fn stop(&mut self) {
        self.pending = None;
        self.remaining = 0;
    }

    /// The pending event, taken to be given: call it on [`Action::Fire`].
    pub fn take(&mut self) -> Option<StepEvent> {
        self.pending.take()
    }

    /// What to do at count `now`: arm the compare, wait a few ticks, or fire.
    pub fn action(&mut self, now: u32) -> Action {
        let elapsed = now.wrapping_sub(self.base);
        if elapsed >= self.remaining {
            // Due or late: the next event counts from this one's due count, so lateness is
            // caught up on, not carried.
            self.base = self.base.wrapping_add(self.remaining);
            self.remaining = 0;
            return Action::Fire;
        }
        self.base = now;
        self.remaining -= elapsed;
        if self.remaining < MIN_LEAD {
            Action::Spin(now.wrapping_add(self.remaining))
        } else {
            Action::Arm(now.wrapping_add(self.remaining.min(LONGEST_ARM)))
        }
    }

    /// Whether `e` changes the direction of an axis it steps: the DIR output must then change
    /// and settle before the pulse. Records the directions as given.
    pub fn dir_changes(&mut self, e: &StepEvent) -> bool {
        let mut changed = false;
        for i in 0..2 {
            if e.step[i] && self.dir[i] != e.dir[i] {
                self.dir[i] = e.dir[i];
                changed = true;
            }
        }
        changed
    }
}

/// Whether the counter has reached `target` at `now` (within half the counter's range).
pub fn reached(now: u32, target: u32) -> bool {
    now.wrapping_sub(target) < 1 << 31
}

/// The controller's milliseconds from the free-running tick counter: exact for any tick rate
/// (the part of a millisecond not yet counted is carried, in thousandths of a tick).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Millis {
    last: u32,
    /// Ticks × 1000 counted but not yet a whole millisecond (less than the tick rate).
    carry: u64,
    ms: u32,
}

impl Millis {
    /// Counting from count `now`, at 0 ms.
    pub const fn new(now: u32) -> Millis {
        Millis {
            last: now,
            carry: 0,
            ms: 0,
        }
    }

    /// The milliseconds at count `now` (wrapping), read at least once per wrap of the counter;
    /// 0 for a tick rate of 0.
    pub fn at(&mut self, now: u32, tick_hz: u32) -> u32 {
        if tick_hz == 0 {
            return self.ms;
        }
        let thousandths = self.carry + u64::from(now.wrapping_sub(self.last)) * 1000;
        self.last = now;
        let whole = thousandths / u64::from(tick_hz);
        self.carry = thousandths % u64::from(tick_hz);
        // The controller's clock wraps (`whole` is under 2^32 · 1000 / 1000).
        self.ms = self.ms.wrapping_add(whole as u32);
        self.ms
    }
}

/// A 16-bit encoder counter widened to 32 bits: read more often than it turns over half its
/// range (32 768 counts), it counts on through its wraps in both directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncoderCount {
    last: u16,
    total: i32,
}

impl EncoderCount {
    /// Counting from the counter's value `raw`, at 0.
    pub const fn new(raw: u16) -> EncoderCount {
        EncoderCount {
            last: raw,
            total: 0,
        }
    }

    /// The count since `new`, the counter now reading `raw`.
    pub fn at(&mut self, raw: u16) -> i32 {
        // The difference read as signed: the shorter way round the 16-bit circle.
        let delta = raw.wrapping_sub(self.last) as i16;
        self.last = raw;
        self.total = self.total.wrapping_add(i32::from(delta));
        self.total
    }
}

/// `counts` of an encoder with `counts_per_rev` counts a turn, in motor steps of a motor with
/// `steps_per_rev` steps a turn, to the nearest step (halves away from zero), saturating; `None`
/// for an encoder of no counts.
pub fn encoder_steps(counts: i32, steps_per_rev: u32, counts_per_rev: u32) -> Option<i32> {
    if counts_per_rev == 0 {
        return None;
    }
    let num = i64::from(counts) * i64::from(steps_per_rev);
    let den = i64::from(counts_per_rev);
    let half = den / 2;
    let q = if num >= 0 {
        (num + half) / den
    } else {
        (num - half) / den
    };
    Some(i32::try_from(q).unwrap_or(if q < 0 { i32::MIN } else { i32::MAX }))
}

#[cfg(test)]
#[path = "tests_step_clock.rs"]
mod tests;
