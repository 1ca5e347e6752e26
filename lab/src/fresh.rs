//! Fresh poses: a reading uses a tip pose sampled after the piece it follows ended. The piece's
//! end is the robot's `progress` header timestamp (its clock), the pose's sample time the tip
//! `TRANSFORM`'s header timestamp (the tracker's clock).
//!
//! Each peer's clock is set against this program's by bounds on its offset (this program's
//! time less the peer's at one instant). Every stamped frame bounds it from above: `arrival -
//! stamp` is the offset plus the frame's delay. A reply bounds it from below: the robot stamps
//! its `holding` when it answers a `hold`, after the `hold` was sent, so `sent - stamp` is at
//! most the offset (the exchange at the start of an insertion, [`Offset::observe_sent`]).
//!
//! The clocks are taken as one (the same machine, or synchronised by NTP or PTP) unless the
//! bounds prove otherwise. Proven apart (the upper bound below zero: the peer's clock ahead;
//! the lower bound above zero: behind), the peer's stamps are moved by the upper bound: a
//! robot's piece end is then taken as late as it can have been, never earlier, so a pose
//! sampled before it is never taken for a fresh one (a reading may wait up to the exchange's
//! reply delay longer than it must). A tracker only streams: no reply bounds its clock from
//! below, so one behind the robot's cannot be told from a tracker that lags; nothing is moved
//! for it, and its poses then look older than they are: the reading waits (and a tracker behind
//! by more than the tracking timeout stops the insertion, `tracking_lost`, saying why). A report
//! or pose without a timestamp (0) is not judged: the newest pose since the previous reading is
//! used.

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

/// A peer clock proven behind by no more than this (s) is taken as this program's: clocks of one
/// machine, read here through `Instant` and `SystemTime`, disagree by microseconds (and moving a
/// lock-step lab's piece end later by them would make its one pose, stamped at that end, stale).
/// A pose sampled this little before a piece's end may then pass as fresh.
pub const BEHIND_WITHIN_S: f64 = 1e-3;

/// Bounds on a peer clock's offset from this program's (s): the smallest `arrival - stamp` seen
/// (above), and the largest `sent - stamp` of a reply (below).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Offset {
    upper: Option<f64>,
    lower: Option<f64>,
}

impl Offset {
    /// Takes in one stamped frame's arrival (this program's clock) and stamp (the peer's).
    pub fn observe(&mut self, arrival_s: f64, stamp_s: f64) {
        let d = arrival_s - stamp_s;
        if d.is_finite() {
            self.upper = Some(self.upper.map_or(d, |m| m.min(d)));
        }
    }

    /// Takes in a reply's stamp (the peer's clock) and when its request was sent (this
    /// program's): the peer stamped it after that.
    pub fn observe_sent(&mut self, sent_s: f64, stamp_s: f64) {
        let d = sent_s - stamp_s;
        if d.is_finite() {
            self.lower = Some(self.lower.map_or(d, |m| m.max(d)));
        }
    }

    /// The upper bound, once a stamped frame came.
    pub fn get(self) -> Option<f64> {
        self.upper
    }

    /// The lower bound, once a reply came.
    pub fn lower(self) -> Option<f64> {
        self.lower
    }

    /// What the peer's stamps are moved by into this program's clock: the upper bound where the
    /// bounds prove the clocks apart (behind by more than [`BEHIND_WITHIN_S`]), else nothing.
    pub fn correction(self) -> f64 {
        let behind = |lo: f64| lo > BEHIND_WITHIN_S;
        match self.upper {
            Some(hi) if hi < 0.0 || self.lower.is_some_and(|lo| behind(lo) && lo <= hi) => hi,
            _ => 0.0,
        }
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
    /// taken for a clock behind, a clock proven ahead is moved back, one proven behind (by a
    /// reply) forward.
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
        // A robot clock 300 ms behind: its `holding` stamped 9.702 for a `hold` sent at 10.0 and
        // answered at 10.003 (this program's clock). Its stamps move forward by at least the
        // offset: a pose sampled 1 ms before the piece truly ended is stale.
        let mut behind = Offset::default();
        behind.observe_sent(10.0, 9.702);
        behind.observe(10.003, 9.702);
        assert!((behind.correction() - 0.301).abs() < 1e-9);
        assert!(!fresh(Some(20.299), Some(20.0), none, behind));
        assert!(fresh(Some(20.302), Some(20.0), none, behind));
        // Proven behind by a tenth of a millisecond: the clocks are taken as one.
        let mut hair = Offset::default();
        hair.observe_sent(10.0001, 10.0);
        hair.observe(10.0003, 10.0);
        assert_eq!(hair.correction(), 0.0);
        // Within the exchange's bounds the clocks are one.
        let mut one = Offset::default();
        one.observe_sent(10.0, 10.001);
        one.observe(10.002, 10.001);
        assert_eq!(one.correction(), 0.0);
        let stamp = Timestamp::from_secs_nanos(7, 500_000_000);
        assert_eq!(seconds(stamp), Some(7.5));
        assert_eq!(seconds(Timestamp::default()), None);
    }
}
