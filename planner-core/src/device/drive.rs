//! The board executes its steered insertion itself: after `SteerDrive` it moves the steering's
//! continuation on its own axes one piece at a time ([`Pieces`]), and each relayed tracker
//! reading, taken once a piece has ended, is answered by the controller and then acted on here:
//! the next piece, the replacement's first piece, or the end. The reading's depth and base roll
//! are the board's own (what it has commanded), not the relay's.

use super::motion::Motion;
use super::Core;
use crate::execute::pieces::Pieces;
use crate::execute::schedule::Op;
use crate::steer::{Command, Reading, SteerReply, TipMeasurement};
use crate::wire::{motion_move, motion_rates, Fault, MotionStatus, ReplyBody};
use needle_motion::{Controller, MotionError, State};

/// The insertion the board drives, if any.
// An explicit tag rather than an `Option`, as for steering (see `DeviceService::new`).
#[allow(clippy::large_enum_variant)]
#[repr(u8)]
pub(super) enum Driven {
    /// The host moves the needle (or nothing is steered).
    Off,
    /// The board moves the pieces of the insertion steered under plan `plan`.
    On {
        plan: u16,
        pieces: Pieces,
        /// Where the axes stood when the drive began (mm, degrees): the entry and the
        /// posture's roll.
        origin: [f32; 2],
        /// The sequence number of the last reading acted on.
        last_seq: Option<u32>,
    },
}

impl super::DeviceService {
    /// The insertion the board drives: how many pieces it has queued and the last of them, as
    /// cut from the continuation (the axes aim it at the exact position the pieces have
    /// reached). `None` when the board drives none. A simulated world takes each piece from
    /// here once the axes have finished it.
    pub fn driven_piece(&self) -> Option<(u32, crate::execute::schedule::Step)> {
        match &self.core.driven {
            Driven::On { pieces, .. } => pieces.last().map(|p| (pieces.count(), p)),
            Driven::Off => None,
        }
    }
}

impl Core {
    /// Forgets the driven insertion (steering starts again: the host moves the needle until a
    /// new `SteerDrive`).
    pub(super) fn stop_driving(&mut self) {
        self.driven = Driven::Off;
    }

    /// Starts driving the insertion steered under plan `id`: the plan's speeds and soft limits
    /// taken, the first piece queued. Answered by the motion status.
    pub(super) fn drive_start(&mut self, id: u16, piece_mm: f32, tx: &mut dyn FnMut(&[u8])) {
        let super::steer::Steered::On { plan, steering } = &self.steering else {
            return self.fault(id, Fault::NotSteering, tx);
        };
        if *plan != id {
            return self.fault(id, Fault::NotSteering, tx);
        }
        if matches!(self.driven, Driven::On { plan, last_seq: None, .. } if plan == id) {
            // A repeat after a lost answer: the first piece is already queued.
            let status = with_core(&mut self.motion, &mut |c| {
                c.heartbeat();
                Ok(MotionStatus::from(c.status()))
            });
            if let Some(Ok(status)) = status {
                return self.send(id, ReplyBody::Motion(status), tx);
            }
        }
        if steering.stats().readings > 0 {
            // The controller has moved on from the entry; the board starts there.
            return self.fault(id, Fault::NotAtEntry, tx);
        }
        let Ok(mut pieces) = Pieces::new(steering.steps(), piece_mm) else {
            return self.fault(id, Fault::BadPieceLength, tx);
        };
        let s = steering.scenario();
        let rates = motion_rates(&s.driver);
        let (needle_mm, twist) = (s.needle.length, s.driver.max_twist_deg);
        let started = with_core(&mut self.motion, &mut |c| {
            c.heartbeat();
            // The twist counts from where the shaft stands: the posture's roll.
            let origin = c.status().position;
            c.set_job_about(rates, needle_mm, twist, origin[1])?;
            queue_next(c, &mut pieces, origin)?;
            Ok((origin, MotionStatus::from(c.status())))
        });
        match started {
            Some(Ok((origin, status))) => {
                self.driven = Driven::On {
                    plan: id,
                    pieces,
                    origin,
                    last_seq: None,
                };
                self.send(id, ReplyBody::Motion(status), tx);
            }
            Some(Err(e)) => self.fault(id, Fault::Motion(e), tx),
            None => self.fault(id, Fault::NoMotion, tx),
        }
    }

    /// Before a reading of a driven insertion reaches the controller: a new reading waits for
    /// the piece to end, and carries the board's commanded depth and base roll. `Err` is the
    /// fault to answer instead; `Ok` without a drive leaves the reading as it came.
    pub(super) fn drive_reading(&mut self, id: u16, m: &mut TipMeasurement) -> Result<(), Fault> {
        let Driven::On {
            plan,
            pieces,
            last_seq,
            ..
        } = &self.driven
        else {
            return Ok(());
        };
        if *plan != id {
            return Ok(());
        }
        m.depth_mm = pieces.depth_mm();
        m.base_deg = pieces.base_deg();
        if last_seq.is_some_and(|last| m.seq <= last) {
            return Ok(()); // a repeated or old reading: answered by the controller, not acted on
        }
        let at_rest = with_core(&mut self.motion, &mut |c| {
            c.heartbeat();
            let status = c.status();
            match (status.state, status.last_fault) {
                (State::Faulted, Some(f)) => Err(MotionError::Faulted(f.cause)),
                (state, _) => Ok(state == State::Armed && status.moves_left == 0),
            }
        });
        let refused = match at_rest {
            Some(Ok(true)) => return Ok(()),
            Some(Ok(false)) => return Err(Fault::PieceMoving),
            Some(Err(e)) => Fault::Motion(e),
            None => Fault::NoMotion,
        };
        // The axes cannot go on: the driven insertion is over.
        self.driven = Driven::Off;
        Err(refused)
    }

    /// Acts on the controller's answer to a reading of a driven insertion: the next piece, the
    /// replacement's first, or the end (the steps ran out, or the controller stopped). `Err`
    /// when the board refused the piece: the drive is over and the host is told why.
    pub(super) fn drive_answer(
        &mut self,
        id: u16,
        seq: u32,
        reply: &SteerReply,
    ) -> Result<(), Fault> {
        let Driven::On {
            plan,
            pieces,
            origin,
            last_seq,
        } = &mut self.driven
        else {
            return Ok(());
        };
        let old = last_seq.is_some_and(|last| seq <= last);
        if *plan != id || reply.reading == Reading::Repeated || old {
            return Ok(());
        }
        *last_seq = Some(seq);
        let go = match &reply.command {
            Command::Continue => true,
            Command::Replace(steps) => pieces.replace(steps).is_ok(),
            Command::Stop(_) => false,
        };
        let moved = if go {
            let origin = *origin;
            with_core(&mut self.motion, &mut |c| queue_next(c, pieces, origin))
        } else {
            Some(Ok(false))
        };
        let (result, moving) = match moved {
            Some(Ok(queued)) => (Ok(()), queued),
            Some(Err(e)) => (Err(Fault::Motion(e)), false),
            None => (Err(Fault::NoMotion), false),
        };
        if !moving {
            self.driven = Driven::Off;
        }
        result
    }
}

/// Queues the next piece on the axes: whether there was one (none left ends the insertion).
fn queue_next(
    c: &mut Controller,
    pieces: &mut Pieces,
    origin: [f32; 2],
) -> Result<bool, MotionError> {
    let base_before = pieces.base_deg();
    let Some(step) = pieces.next_piece() else {
        return Ok(false);
    };
    let at = c.status().position;
    let op = on_track(step.op, origin, at, pieces.depth_mm(), base_before);
    c.execute(&[motion_move(&op)]).map(|()| true)
}

/// `op` aimed at the exact position the pieces have reached from `origin`, from where the axes
/// stand (`at`): each piece then ends on the step nearest that position, and the rounding of
/// a hundred pieces does not add up. The insertion to `depth_after`; a rotation to the roll the
/// pieces had before it plus its angle (whole turns a spin left on the shaft aside).
fn on_track(op: Op, origin: [f32; 2], at: [f32; 2], depth_after: f32, base_before: f32) -> Op {
    let length_mm = origin[0] + depth_after - at[0];
    match op {
        Op::Rotate { angle_deg } => {
            let off = libm::remainderf(origin[1] + base_before - at[1], 360.0);
            Op::Rotate {
                angle_deg: angle_deg + off,
            }
        }
        Op::Insert { .. } => Op::Insert { length_mm },
        Op::InsertSpin { turns, .. } => Op::InsertSpin { length_mm, turns },
        Op::InsertDuty { duty, .. } => Op::InsertDuty { length_mm, duty },
    }
}

/// Calls `f` with the board's motion core: `None` without axes (or a board that cannot lend
/// its core now).
fn with_core<R>(
    motion: &mut Motion,
    f: &mut dyn FnMut(&mut Controller) -> Result<R, MotionError>,
) -> Option<Result<R, MotionError>> {
    match motion {
        #[cfg(feature = "owned-motion")]
        Motion::On(c) => Some(f(c)),
        Motion::Port(port) => {
            let mut out = None;
            port.with_motion(&mut |c| out = Some(f(c)));
            out
        }
        Motion::Off => None,
    }
}
