//! The interlocks of time and the robot's stop: who is silent (the robot owing a report, the
//! tracker owing a fresh pose after one, a peer that sends no OpenIGTLink), and the stop sent
//! whatever ended the insertion.

use super::{Ending, Event, Session};
use crate::robot::{RobotCommand, RobotReport};
use needle_igtl::Message;
use std::sync::atomic::Ordering;
use std::time::Instant;

impl Session<'_> {
    /// The interlocks of time. While the robot owes a report, only the robot's timeout runs: a
    /// robot that does not answer leaves a lock-step tracker nothing to send, and its silence
    /// must not be blamed on the tracker. Once the robot reported, the tracker's timeout runs
    /// from the report. A peer that sent bytes but never one OpenIGTLink frame is named so.
    pub(super) fn timed_out(&self) -> Option<Ending> {
        if let Some(t) = self.robot_clock {
            return (t.elapsed() > self.config.robot_timeout).then(|| self.robot_silence());
        }
        // A fresh pose is taken as soon as it is in: while a report waits, none came.
        self.pending?;
        if self.tracker_clock.elapsed() <= self.config.tracking_timeout {
            return None;
        }
        let frames = self.state().frames_decoded;
        let babbled = self.tracker_bytes.load(Ordering::Relaxed) > 0 && frames == 0;
        Some(if babbled {
            Ending::TrackerNotOpenIgtlink
        } else {
            Ending::TrackingLost
        })
    }

    /// Why the robot is silent: it sent bytes but not one OpenIGTLink frame, or nothing.
    pub(super) fn robot_silence(&self) -> Ending {
        if self.robot_bytes.load(Ordering::Relaxed) > 0 && self.robot_frames == 0 {
            Ending::RobotNotOpenIgtlink
        } else {
            Ending::RobotNotAnswering
        }
    }

    /// Tells the robot to stop (holding first when tracking was lost) and waits for its word.
    pub(super) fn stop_robot(&mut self, ending: Ending) {
        // A robot that sensed a collision has stopped of itself and takes no more words.
        if matches!(ending, Ending::RobotStopped | Ending::RobotCollided) {
            self.outcome.robot_stopped = true;
            return;
        }
        if ending == Ending::RobotDisconnected {
            return;
        }
        if ending == Ending::TrackingLost {
            let _ = self.command(RobotCommand::Hold);
        }
        // The controller's stop went out with its answer.
        let sent = matches!(ending, Ending::Controller(_));
        if !sent && self.command(RobotCommand::Stop).is_err() {
            return;
        }
        let deadline = Instant::now() + self.config.robot_timeout;
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            match self.events.recv_timeout(left) {
                Ok(Event::Robot(arrival)) => {
                    if let (Ok(f), _) = *arrival {
                        let Message::String(s) = f.message else {
                            continue;
                        };
                        if s.text.parse() == Ok(RobotReport::Stopped) {
                            self.outcome.robot_stopped = true;
                            return;
                        }
                    }
                }
                Ok(_) => {}
                Err(_) => return,
            }
        }
    }
}
