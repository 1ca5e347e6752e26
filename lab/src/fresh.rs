//! Fresh poses: a reading uses a tip pose sampled after the piece it follows ended. The piece's
//! end is the robot's `progress` header timestamp (its clock), the pose's sample time the tip
//! `TRANSFORM`'s header timestamp (the tracker's clock).
//!
//! The clocks are compared as one (the same machine, or synchronised by NTP or PTP) unless a
//! frame proves otherwise. Each peer's clock is set against this program's by the smallest
//! `arrival - stamp` seen over its frames: the peer's smallest delay minus how far its clock is
//! ahead. Below zero, the peer's clock is ahead by at least that much, and its stamps are moved
//! back by it (late by at most the smallest delay, which is the bound). Above zero it cannot
//! tell a clock behind from a delay (a tracker lagging 100 ms looks like one 100 ms behind), so
//! nothing is moved: the pose's age then counts the lag, and a pose sampled before the piece
//! ended is never taken for a fresh one; a tracker clock behind the robot's by more than the
//! tracking timeout would stop the insertion (`tracking_lost`). A report or pose without a
//! timestamp (0) is not judged: the newest pose since the previous reading is used.

use needle_igtl::Timestamp;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

/// A header timestamp in seconds since the epoch; `None`: unused (0).
pub fn seconds(t: Timestamp) -> Option<f64> {
    (t != Timestamp::default())
        .then(|| f64::from(t.seconds) + f64::from(t.fraction) / 4_294_967_296.0)
}

/// This program's wall clock at an `Instant` (seconds since the epoch), from one reading of
/// both clocks, so that arrivals keep their order and spacing.
#[derive(Clone, Copy, Debug)]
pub struct HostClock {
    start: Instant,
    unix_s: f64,
}

impl Default for HostClock {
    fn default() -> Self {
        let unix_s = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        HostClock {
            start: Instant::now(),
            unix_s,
        }
    }
}

impl HostClock {
    /// The wall-clock time of `at`.
    pub fn unix(&self, at: Instant) -> f64 {
        match at.checked_duration_since(self.start) {
            Some(d) => self.unix_s + d.as_secs_f64(),
            None => self.unix_s - self.start.duration_since(at).as_secs_f64(),
        }
    }
}

/// A peer clock's offset from this program's (s): the smallest `arrival - stamp` seen.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Offset(Option<f64>);

impl Offset {
    /// Takes in one stamped frame's arrival (this program's clock) and stamp (the peer's).
    pub fn observe(&mut self, arrival_s: f64, stamp_s: f64) {
        let d = arrival_s - stamp_s;
        if d.is_finite() {
            self.0 = Some(self.0.map_or(d, |m| m.min(d)));
        }
    }

    /// The estimate, once a stamped frame came.
    pub fn get(self) -> Option<f64> {
        self.0
    }
}

impl Offset {
    /// What the peer's stamps are moved by into this program's clock: back by how far the
    /// peer's clock is proven ahead, else nothing.
    pub fn correction(self) -> f64 {
        self.0.map_or(0.0, |d| d.min(0.0))
    }
}

/// Whether a pose sampled at `sample_s` (the tracker's clock) was sampled once the piece that
/// ended at `end_s` (the robot's clock) had ended, each stamp moved by its clock's correction.
/// Without both stamps it cannot be judged and passes.
pub fn fresh(sample_s: Option<f64>, end_s: Option<f64>, tracker: Offset, robot: Offset) -> bool {
    match (sample_s, end_s) {
        (Some(s), Some(e)) => s + tracker.correction() >= e + robot.correction(),
        _ => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pose sampled before the piece ended is not fresh, at or after it is; a lag is not
    /// taken for a clock behind, a clock proven ahead is moved back.
    #[test]
    fn freshness_against_the_pieces_end() {
        let none = Offset::default();
        assert!(!fresh(Some(99.9), Some(100.0), none, none));
        assert!(fresh(Some(100.0), Some(100.0), none, none));
        assert!(
            fresh(None, Some(100.0), none, none),
            "unstamped: not judged"
        );
        // Poses arriving 100 ms after their stamp: a lag, nothing moved.
        let mut lagging = Offset::default();
        lagging.observe(10.1, 10.0);
        assert_eq!(lagging.correction(), 0.0);
        assert!(!fresh(Some(10.0), Some(10.05), lagging, none));
        // A tracker clock a second ahead: its pose arrived "before" it was sampled.
        let mut ahead = Offset::default();
        ahead.observe(10.001, 11.0);
        assert!((ahead.correction() + 0.999).abs() < 1e-9);
        assert!(fresh(Some(11.0), Some(10.0), ahead, none));
        assert!(!fresh(Some(10.9), Some(10.0), ahead, none));
        let stamp = Timestamp::from_secs_nanos(7, 500_000_000);
        assert_eq!(seconds(stamp), Some(7.5));
        assert_eq!(seconds(Timestamp::default()), None);
    }
}
