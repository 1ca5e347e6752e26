//! Motion on the device: the board's motion core behind the link's motion requests.
//!
//! The board hands the service its axes ([`DeviceService::set_motion`]); from then on it steps
//! the core from its timer and feeds it the clock and the inputs through
//! [`DeviceService::motion`], and the host's requests reach it here. A board whose interrupts
//! step the core while the service plans keeps the core itself, where its interrupts reach it,
//! and lends it to the service for each request ([`DeviceService::set_motion_port`]). Without
//! axes a motion request is answered with [`Fault::NoMotion`].

use super::{Core, DeviceService};
use crate::wire::{motion_move, motion_rates, Fault, MotionRequest, MotionStatus, ReplyBody};
use needle_motion::{Controller, MotionError, Move, QUEUE};
#[cfg(feature = "owned-motion")]
use needle_motion::{MotionConfig, SafetyConfig};

/// The motion core, if the board drives axes.
// An explicit tag rather than an `Option`, as for steering: a niche would put the whole
// service in `.data` instead of `.bss` (see `DeviceService::new`). No heap to box it in.
#[allow(clippy::large_enum_variant)]
#[repr(u8)]
pub(super) enum Motion {
    /// No axes.
    Off,
    /// The board's axes.
    #[cfg(feature = "owned-motion")]
    On(Controller),
    /// The board's axes, kept by the board and lent for each request.
    Port(&'static dyn MotionPort),
}

/// A motion core the board keeps, where its step and input interrupts reach it, lent to the
/// service one request at a time (on a microcontroller, inside a critical section).
pub trait MotionPort: Sync {
    /// Calls `f` with the core, or not at all when the board cannot lend it (the request is
    /// then answered as by a board without axes).
    fn with_motion(&self, f: &mut dyn FnMut(&mut Controller));
}

impl DeviceService {
    /// Drive axes: the board's motion set-up (the rates and soft limits are replaced by each
    /// move request's plan). The core starts disarmed and unhomed.
    #[cfg(feature = "owned-motion")]
    pub fn set_motion(
        &mut self,
        config: MotionConfig,
        safety: SafetyConfig,
    ) -> Result<(), MotionError> {
        self.core.motion = Motion::On(Controller::new(config, safety)?);
        Ok(())
    }

    /// Drive axes whose core the board keeps: each motion request borrows it through `port`.
    pub fn set_motion_port(&mut self, port: &'static dyn MotionPort) {
        self.core.motion = Motion::Port(port);
    }

    /// The motion core, for the board's timer (steps) and its main loop (clock and inputs);
    /// `None` without axes, or when the board keeps the core ([`Self::set_motion_port`]).
    pub fn motion(&mut self) -> Option<&mut Controller> {
        match &mut self.core.motion {
            #[cfg(feature = "owned-motion")]
            Motion::On(c) => Some(c),
            Motion::Off | Motion::Port(_) => None,
        }
    }
}

impl Core {
    /// Answers a motion request with the core's status, or why it was refused.
    pub(super) fn motion_request(
        &mut self,
        id: u16,
        req: &MotionRequest,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        let body = match &mut self.motion {
            #[cfg(feature = "owned-motion")]
            Motion::On(c) => answer(c, req),
            Motion::Port(port) => {
                let mut body = None;
                port.with_motion(&mut |c| body = Some(answer(c, req)));
                match body {
                    Some(b) => b,
                    None => return self.fault(id, Fault::NoMotion, tx),
                }
            }
            Motion::Off => return self.fault(id, Fault::NoMotion, tx),
        };
        if matches!(req, MotionRequest::Move { .. }) && matches!(body, ReplyBody::Motion(_)) {
            self.stats.motion_moves = self.stats.motion_moves.wrapping_add(1);
        }
        self.send(id, body, tx);
    }
}

/// The reply to `req`, applied to `c`.
fn answer(c: &mut Controller, req: &MotionRequest) -> ReplyBody {
    // Every request is the host's heartbeat.
    c.heartbeat();
    match apply(c, req) {
        Ok(()) => ReplyBody::Motion(MotionStatus::from(c.status())),
        Err(e) => ReplyBody::Fault(Fault::Motion(e)),
    }
}

fn apply(c: &mut Controller, req: &MotionRequest) -> Result<(), MotionError> {
    match req {
        MotionRequest::Status => Ok(()),
        MotionRequest::Arm => c.arm(),
        MotionRequest::Disarm => c.disarm(),
        MotionRequest::Home => c.home(),
        MotionRequest::Move {
            driver,
            needle_mm,
            steps,
        } => {
            c.set_job(motion_rates(driver), *needle_mm, driver.max_twist_deg)?;
            let mut moves = heapless::Vec::<Move, QUEUE>::new();
            for s in steps {
                moves
                    .push(motion_move(&s.op))
                    .map_err(|_| MotionError::QueueFull)?;
            }
            c.execute(&moves)
        }
        MotionRequest::Hold => c.hold(),
        MotionRequest::Resume => c.resume(),
        MotionRequest::Stop => c.stop(),
        MotionRequest::ClearFault => {
            let inputs = c.inputs();
            c.clear_fault(&inputs)
        }
        MotionRequest::Reset => c.reset(),
        MotionRequest::EStop => {
            c.estop();
            Ok(())
        }
    }
}
