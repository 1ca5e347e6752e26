//! The simulated lab's robot: its connection, the commands that arrive on it (read on their
//! own thread), and its reports, each stamped.

use anyhow::Result;
use needle_igtl::{FrameInfo, Message, StringMessage, Timestamp};
use needle_lab::robot::{RobotCommand, RobotReport, COMMAND_DEVICE, REPORT_DEVICE};
use needle_lab::wire::{now, read_frames, send_with};
use planner_core::execute::schedule::Step;
use std::net::TcpStream;
use std::sync::mpsc::{channel, Receiver};

/// What the robot heard.
pub(super) enum Word {
    Go,
    Replace(Vec<Step>),
    Stop,
    Lost,
}

/// The simulated robot of one insertion: its connection and what arrives on it.
pub(super) struct Robot {
    conn: TcpStream,
    pub(super) commands: Receiver<RobotCommand>,
    pub(super) pieces: u32,
    silent_after: Option<u32>,
    /// How far the robot's clock runs ahead of the machine's (ms; negative: behind).
    clock_offset_ms: i64,
}

impl Robot {
    pub(super) fn new(
        conn: TcpStream,
        silent_after: Option<u32>,
        clock_offset_ms: i64,
    ) -> Result<Robot> {
        conn.set_nodelay(true)?;
        let (tx, commands) = channel();
        read_frames(
            conn.try_clone()?,
            move |(frame, _)| match frame {
                Ok(f) if f.info.device_name == COMMAND_DEVICE => match f.message {
                    Message::String(s) => match s.text.parse::<RobotCommand>() {
                        Ok(c) => tx.send(c).is_ok(),
                        Err(e) => {
                            eprintln!("hil-sim lab: robot command refused: {e}");
                            true
                        }
                    },
                    _ => true,
                },
                _ => true,
            },
            || {},
        );
        Ok(Robot {
            conn,
            commands,
            pieces: 0,
            silent_after,
            clock_offset_ms,
        })
    }

    pub(super) fn report(&mut self, r: RobotReport) {
        self.report_at(r, now());
    }

    /// Reports `r` with the header timestamp `at`.
    pub(super) fn report_at(&mut self, r: RobotReport, at: Timestamp) {
        if self.silent_after.is_some_and(|n| self.pieces > n) {
            return;
        }
        let (Ok(text), Ok(mut info)) = (
            StringMessage::ascii(&r.to_string()),
            FrameInfo::new(REPORT_DEVICE),
        ) else {
            return;
        };
        info.timestamp = on_own_clock(at, self.clock_offset_ms);
        // A host that left is seen when its next word does not come.
        let _ = send_with(&mut self.conn, &info, &Message::String(text));
    }

    /// The `count` steps of a list whose `steps` word has arrived.
    pub(super) fn steps(&mut self, count: usize) -> Option<Vec<Step>> {
        let mut out = Vec::with_capacity(count);
        while out.len() < count {
            match self.commands.recv().ok()? {
                RobotCommand::Step(s) => out.push(s),
                _ => return None,
            }
        }
        Some(out)
    }

    /// The host's next word; `hold` is reported and waited out.
    pub(super) fn word(&mut self) -> Word {
        loop {
            match self.commands.recv() {
                Err(_) => return Word::Lost,
                Ok(RobotCommand::Go) => return Word::Go,
                Ok(RobotCommand::Stop) => return Word::Stop,
                Ok(RobotCommand::Hold) => self.report(RobotReport::Holding),
                Ok(RobotCommand::Steps { count }) => {
                    return self.steps(count).map_or(Word::Lost, Word::Replace)
                }
                Ok(RobotCommand::Step(_)) => {
                    eprintln!("hil-sim lab: a step outside a step list is ignored");
                }
                Ok(RobotCommand::Posture { .. }) => {
                    eprintln!("hil-sim lab: a posture once inserting is ignored");
                }
            }
        }
    }
}

/// `at` on a clock running `offset_ms` ahead (negative: behind); an unused stamp (0) stays so.
fn on_own_clock(at: Timestamp, offset_ms: i64) -> Timestamp {
    if at == Timestamp::default() {
        return at;
    }
    // The 64-bit stamp counts 2^-32 s.
    let shift = offset_ms.saturating_mul(1 << 32) / 1000;
    let bits = i128::from(at.to_bits()) + i128::from(shift);
    Timestamp::from_bits(bits.clamp(1, i128::from(u64::MAX)) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A clock 300 ms behind stamps 0.3 s earlier; an unused stamp is left unused.
    #[test]
    fn a_clock_apart_shifts_the_stamps() {
        let at = Timestamp::from_secs_nanos(100, 0);
        let behind = on_own_clock(at, -300);
        assert_eq!(behind.seconds, 99);
        assert!((behind.subsec_nanos() as i64 - 700_000_000).abs() <= 1);
        assert_eq!(on_own_clock(at, 0), at);
        assert_eq!(on_own_clock(Timestamp::default(), 5), Timestamp::default());
    }
}
