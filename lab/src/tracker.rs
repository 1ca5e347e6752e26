//! The tracker's side of a session, kept in bounded memory whatever the tracker sends.
//!
//! Frames are read on the connection's own thread and taken in there as they arrive: the newest
//! tip pose waits in one slot, the newest target and the first registration in one each, counts
//! and a bounded queue of log lines beside them. The session is woken by at most one pending notice. So a tracker that
//! streams at 1 kHz, or flushes a burst, costs no backlog: the controller always gets the newest
//! pose, and a pose replaced before a reading took it is counted (`superseded_poses`).
//!
//! A pose whose header timestamp is the one of the pose the previous reading used is the same
//! sample sent again (a stream repeating its newest sample, or a tracker re-sending a lost tool's
//! last pose): it is not used twice (`repeated_poses`), and it does not count as the tracker
//! being heard. A timestamp of zero (unused) is never taken for a repeat.
//!
//! The target is used once too: a reading takes the newest target that arrived since the
//! previous one, or none (imaging that sees the target less often than the tracker the tip),
//! and a copy of a used target (by its timestamp, as for the tip) is no new one.
//!
//! A pose flagged invalid (v3 metadata `TransformStatus` other than `OK`, or after a `STATUS` of
//! the tip that is not OK, until an OK one) fills the slot as a pose-less arrival: the reading
//! goes to the controller as a dropout.

use super::fresh::{fresh, seconds, HostClock, Offset};
use super::wire::{tip_pose, Arrival};
use needle_igtl::{Message, StatusCode, Timestamp, Transform};
use planner_core::steer::Pose;
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::VecDeque;
use std::time::Instant;

/// Log lines (rejections, refused registrations) kept between two looks of the session; beyond
/// it they are counted (in [`TrackerCounts`]) but not logged one by one, so a stream of garbage
/// cannot grow memory.
pub const NOTES_KEPT: usize = 64;

/// A later registration differing from the first by more than this in a rotation entry is
/// refused.
pub const REGISTRATION_ROTATION_TOLERANCE: f32 = 1e-4;
/// ... or by more than this in its translation (mm).
pub const REGISTRATION_TRANSLATION_TOLERANCE_MM: f32 = 1e-2;

/// The device names a session listens to.
#[derive(Clone, Debug)]
pub struct TrackerNames {
    /// The tip's `TRANSFORM` (and `STATUS`).
    pub tip: String,
    /// The target's `TRANSFORM`.
    pub target: String,
    /// The registration's `TRANSFORM` (tracker to scenario frame), if it comes by the stream.
    pub registration: Option<String>,
}

/// What the tracker sent that was not used as sent, counted over the session.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TrackerCounts {
    /// Frames the codec rejected (bad CRC, bad size, not rigid, a name not UTF-8, ...).
    pub rejected_frames: u32,
    /// Tip poses flagged invalid and not used.
    pub invalid_poses: u32,
    /// Tip poses replaced by a newer one before a reading took them.
    pub superseded_poses: u32,
    /// Tip poses with the timestamp of the pose the previous reading used: not used again.
    pub repeated_poses: u32,
    /// Frames that decode but carry no name (or type) the session listens to.
    pub ignored_frames: u32,
    /// Registration `TRANSFORM`s that differ from the first one received, not applied.
    pub registrations_refused: u32,
    /// Tip poses sampled before the piece a reading follows ended: not used.
    pub stale_poses: u32,
}

/// The newest tip pose not yet taken by a reading.
#[derive(Clone, Copy, Debug)]
pub struct TipArrival {
    /// The pose in the tracker's frame; `None`: flagged invalid.
    pub pose: Option<Pose>,
    /// When its bytes arrived (the first copy's, for a sample sent again before it was used).
    pub at: Instant,
    /// Its header timestamp.
    pub stamp: Timestamp,
}

/// The tracker's state, shared by its reader thread and the session.
#[derive(Debug)]
pub struct TrackerState {
    /// The newest tip pose not yet used.
    pub tip: Option<TipArrival>,
    /// The newest target not yet used, in the tracker's frame, and its header timestamp.
    pub target: Option<([f32; 3], Timestamp)>,
    /// The timestamp of the target the previous reading used.
    used_target_stamp: Option<Timestamp>,
    /// The first registration `TRANSFORM` received: the one used for the whole session.
    pub registration: Option<Transform>,
    /// When the last tip `TRANSFORM` that was not a repeat arrived, used or not.
    pub last_tip_at: Option<Instant>,
    /// The timestamp of the pose the previous reading used.
    used_stamp: Option<Timestamp>,
    /// Counts over the session.
    pub counts: TrackerCounts,
    /// Frames that decoded, of any name: none while bytes come is a peer that does not speak
    /// OpenIGTLink.
    pub frames_decoded: u32,
    /// This program's clock, shared with the session.
    pub clock: HostClock,
    /// The tracker clock's offset from this program's, from the stamped tip poses.
    pub offset: Offset,
    /// Log lines not yet written (event, fields), at most [`NOTES_KEPT`].
    pub notes: VecDeque<(&'static str, Value)>,
    tip_status_ok: bool,
    /// A notice is on its way to the session: no second one is sent.
    pub notice_pending: bool,
}

impl Default for TrackerState {
    fn default() -> Self {
        TrackerState {
            tip: None,
            target: None,
            used_target_stamp: None,
            registration: None,
            last_tip_at: None,
            used_stamp: None,
            counts: TrackerCounts::default(),
            frames_decoded: 0,
            clock: HostClock::default(),
            offset: Offset::default(),
            notes: VecDeque::new(),
            tip_status_ok: true,
            notice_pending: false,
        }
    }
}

impl TrackerState {
    /// Takes in one frame (or rejection) off the tracker's connection.
    pub fn on_frame(&mut self, names: &TrackerNames, (frame, at): Arrival) {
        let frame = match frame {
            Ok(f) => f,
            Err(e) => {
                self.counts.rejected_frames = self.counts.rejected_frames.saturating_add(1);
                self.note("rejected", json!({ "error": format!("{e:?}") }));
                return;
            }
        };
        self.frames_decoded = self.frames_decoded.saturating_add(1);
        let name = frame.info.device_name.as_str();
        let flagged = frame
            .info
            .extended
            .as_ref()
            .and_then(|e| e.metadata.get("TransformStatus"))
            .is_some_and(|s| s != "OK");
        match frame.message {
            Message::Transform(t) if name == names.tip => {
                let stamp = frame.info.timestamp;
                let sent = stamp != Timestamp::default();
                if let Some(s) = seconds(stamp) {
                    self.offset.observe(self.clock.unix(at), s);
                }
                if sent && self.used_stamp == Some(stamp) {
                    self.counts.repeated_poses = self.counts.repeated_poses.saturating_add(1);
                    return;
                }
                let valid = self.tip_status_ok && !flagged;
                if !valid {
                    self.counts.invalid_poses = self.counts.invalid_poses.saturating_add(1);
                }
                let mut arrival = TipArrival {
                    pose: valid.then(|| tip_pose(&t)),
                    at,
                    stamp,
                };
                if let Some(old) = self.tip.replace(arrival) {
                    self.counts.superseded_poses = self.counts.superseded_poses.saturating_add(1);
                    if sent && old.stamp == stamp {
                        // The same sample again: its latency runs from its first copy.
                        arrival.at = old.at;
                        self.tip = Some(arrival);
                    }
                }
                self.last_tip_at = Some(at);
            }
            Message::Transform(t) if name == names.target => {
                let stamp = frame.info.timestamp;
                // A target sent again after a reading used it (a stream repeating its newest
                // sample) is no new image.
                if stamp == Timestamp::default() || self.used_target_stamp != Some(stamp) {
                    self.target = Some((t.translation(), stamp));
                }
            }
            Message::Transform(t) if names.registration.as_deref() == Some(name) => {
                self.on_registration(t);
            }
            Message::Status(s) if name == names.tip => {
                self.tip_status_ok = s.code == StatusCode::OK
            }
            _ => self.counts.ignored_frames = self.counts.ignored_frames.saturating_add(1),
        }
    }

    /// Takes the newest tip pose for a reading; a later copy of it is then a repeat.
    pub fn take_tip(&mut self) -> Option<TipArrival> {
        let tip = self.tip.take()?;
        self.used_stamp = Some(tip.stamp);
        Some(tip)
    }

    /// Takes the newest tip pose for a reading if it was sampled once the piece that ended at
    /// `end_s` (the robot's clock, whose offset is `robot`) had ended; a pose sampled before is
    /// dropped and counted (`stale_poses`).
    pub fn take_fresh_tip(&mut self, end_s: Option<f64>, robot: Offset) -> Option<TipArrival> {
        let tip = self.tip?;
        if fresh(seconds(tip.stamp), end_s, self.offset, robot) {
            return self.take_tip();
        }
        self.tip = None;
        self.counts.stale_poses = self.counts.stale_poses.saturating_add(1);
        None
    }

    /// Takes the newest target for a reading (`None`: no new one since the last reading); a
    /// later copy of it is then a repeat.
    pub fn take_target(&mut self) -> Option<[f32; 3]> {
        let (target, stamp) = self.target.take()?;
        self.used_target_stamp = Some(stamp);
        Some(target)
    }

    /// The first registration is kept; a later one that differs from it is refused (counted and
    /// logged): the frame the insertion started in does not jump under the controller.
    fn on_registration(&mut self, t: Transform) {
        let Some(first) = self.registration else {
            self.registration = Some(t);
            return;
        };
        if differs(&first, &t) {
            self.counts.registrations_refused = self.counts.registrations_refused.saturating_add(1);
            let (rotation, translation_mm) = (t.rotation(), t.translation());
            self.note(
                "registration_refused",
                json!({ "rotation": rotation, "translation_mm": translation_mm }),
            );
        }
    }

    fn note(&mut self, event: &'static str, fields: Value) {
        if self.notes.len() < NOTES_KEPT {
            self.notes.push_back((event, fields));
        }
    }
}

/// Whether two registrations differ by more than the tolerances.
pub fn differs(a: &Transform, b: &Transform) -> bool {
    let (ra, rb) = (a.rotation(), b.rotation());
    let turned = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .any(|(i, j)| (ra[i][j] - rb[i][j]).abs() > REGISTRATION_ROTATION_TOLERANCE);
    let (ta, tb) = (a.translation(), b.translation());
    let moved = (0..3).any(|i| (ta[i] - tb[i]).abs() > REGISTRATION_TRANSLATION_TOLERANCE_MM);
    turned || moved
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::tip_transform;
    use needle_igtl::{Error, Frame, FrameInfo};

    fn names() -> TrackerNames {
        TrackerNames {
            tip: "NeedleTipToReference".into(),
            target: "TargetToReference".into(),
            registration: Some("ReferenceToScenario".into()),
        }
    }

    fn tip_frame(z: f32) -> Frame {
        let t = tip_transform([0.0, 0.0, z], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]).unwrap();
        Frame {
            info: FrameInfo::new("NeedleTipToReference").unwrap(),
            message: Message::Transform(t),
        }
    }

    fn stamped(z: f32, seconds: u32) -> Arrival {
        let mut f = tip_frame(z);
        f.info.timestamp = Timestamp::from_secs_nanos(seconds, 0);
        (Ok(f), Instant::now())
    }

    /// A sample sent again keeps its first arrival while unused, and once a reading used it,
    /// its copies are repeats: not used again, not news of the tracker. Unstamped poses are
    /// never repeats.
    #[test]
    fn a_sample_sent_again_is_not_used_twice() {
        let mut s = TrackerState::default();
        s.on_frame(&names(), stamped(1.0, 7));
        let first = s.tip.unwrap().at;
        s.on_frame(&names(), stamped(1.0, 7));
        assert_eq!(s.counts.superseded_poses, 1);
        let used = s.take_tip().unwrap();
        assert_eq!(used.at, first);
        let heard = s.last_tip_at;
        s.on_frame(&names(), stamped(1.0, 7));
        assert!(s.tip.is_none());
        assert_eq!((s.counts.repeated_poses, s.last_tip_at), (1, heard));
        s.on_frame(&names(), stamped(2.0, 8));
        assert_eq!(s.take_tip().unwrap().pose.unwrap().position[2], 2.0);
        s.on_frame(&names(), stamped(3.0, 0));
        s.take_tip().unwrap();
        s.on_frame(&names(), stamped(3.0, 0));
        assert!(s.tip.is_some(), "no timestamp: no repeat");
    }

    /// A million poses with no reading in between hold one pose: the newest; every other one is
    /// counted as superseded. Rejections are all counted, kept for the log only up to the bound.
    #[test]
    fn a_flood_is_held_in_bounded_memory_and_counted() {
        let mut s = TrackerState::default();
        let n = 1_000_000u32;
        for i in 0..n {
            s.on_frame(&names(), (Ok(tip_frame(i as f32 * 1e-3)), Instant::now()));
        }
        let newest = s.tip.expect("the newest pose").pose.expect("valid");
        assert_eq!(newest.position[2], (n - 1) as f32 * 1e-3);
        assert_eq!(s.counts.superseded_poses, n - 1);
        for _ in 0..10_000 {
            s.on_frame(&names(), (Err(Error::BadCrc), Instant::now()));
        }
        assert_eq!(s.counts.rejected_frames, 10_000);
        assert_eq!(s.notes.len(), NOTES_KEPT);
        assert!(s
            .notes
            .iter()
            .all(|(e, f)| *e == "rejected" && f["error"] == "BadCrc"));
    }

    /// A target is used once: a reading after no new image has none; a copy of the used one
    /// (same timestamp) is no new image, a new timestamp is; an unstamped one is always new.
    #[test]
    fn a_target_is_used_once() {
        let target = |x: f32, seconds: u32| -> Arrival {
            let mut f = tip_frame(x);
            f.info = FrameInfo::new("TargetToReference").unwrap();
            f.info.timestamp = Timestamp::from_secs_nanos(seconds, 0);
            (Ok(f), Instant::now())
        };
        let mut s = TrackerState::default();
        assert_eq!(s.take_target(), None);
        s.on_frame(&names(), target(1.0, 7));
        s.on_frame(&names(), target(2.0, 8));
        assert_eq!(s.take_target(), Some([0.0, 0.0, 2.0]), "the newest");
        assert_eq!(s.take_target(), None, "no new image");
        s.on_frame(&names(), target(2.0, 8));
        assert_eq!(s.take_target(), None, "a copy of the used one");
        s.on_frame(&names(), target(3.0, 9));
        assert_eq!(s.take_target(), Some([0.0, 0.0, 3.0]));
        for _ in 0..2 {
            s.on_frame(&names(), target(4.0, 0));
            assert_eq!(
                s.take_target(),
                Some([0.0, 0.0, 4.0]),
                "unstamped: always new"
            );
        }
        assert_eq!(s.counts.ignored_frames, 0);
    }

    #[test]
    fn names_not_listened_to_are_ignored_and_counted() {
        let mut s = TrackerState::default();
        let mut f = tip_frame(1.0);
        // 20 bytes, no terminator, one letter off the tip's name: not the tip.
        f.info = FrameInfo::new("NeedleTipToReferencf").unwrap();
        s.on_frame(&names(), (Ok(f), Instant::now()));
        assert!(s.tip.is_none());
        assert_eq!(s.counts.ignored_frames, 1);
    }

    /// The first registration is used; the same again passes, one a little off (within the
    /// tolerance) too; one moved 0.1 mm is refused, counted and logged, and the first stays.
    #[test]
    fn a_later_different_registration_is_refused() {
        let mut s = TrackerState::default();
        for z in [5.0, 5.0, 5.005, 5.1, 5.0] {
            let mut r = tip_frame(z);
            r.info = FrameInfo::new("ReferenceToScenario").unwrap();
            s.on_frame(&names(), (Ok(r), Instant::now()));
        }
        let reg = s.registration.expect("the registration");
        assert_eq!(reg.translation(), [0.0, 0.0, 5.0]);
        assert_eq!(s.counts.registrations_refused, 1);
        assert_eq!(s.counts.ignored_frames, 0);
        let (event, fields) = &s.notes[0];
        assert_eq!(*event, "registration_refused");
        assert_eq!(fields["translation_mm"][2], 5.1_f32 as f64);
    }
}
