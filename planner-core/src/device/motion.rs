//! Motion on the device: the board's motion core behind the link's motion requests.
//!
//! The board hands the service its axes ([`DeviceService::set_motion`]); from then on it steps
//! the core from its timer and feeds it the clock and the inputs through
//! [`DeviceService::motion`], and the host's requests reach it here. Without axes a motion
//! request is answered with [`Fault::NoMotion`].

use super::{Core, DeviceService};
use crate::wire::{motion_move, Fault, MotionRequest, MotionStatus, ReplyBody};
use needle_motion::{Controller, MotionConfig, MotionError, Move, Rates, SafetyConfig, QUEUE};

/// The motion core, if the board drives axes.
// An explicit tag rather than an `Option`, as for steering: a niche would put the whole
// service in `.data` instead of `.bss` (see `DeviceService::new`). No heap to box it in.
#[allow(clippy::large_enum_variant)]
#[repr(u8)]
pub(super) enum Motion {
    /// No axes.
    Off,
    /// The board's axes.
    On(Controller),
}

impl DeviceService {
    /// Drive axes: the board's motion set-up (the rates and soft limits are replaced by each
    /// move request's plan). The core starts disarmed and unhomed.
    pub fn set_motion(
        &mut self,
        config: MotionConfig,
        safety: SafetyConfig,
    ) -> Result<(), MotionError> {
        self.core.motion = Motion::On(Controller::new(config, safety)?);
        Ok(())
    }

    /// The motion core, for the board's timer (steps) and its main loop (clock and inputs).
    pub fn motion(&mut self) -> Option<&mut Controller> {
        match &mut self.core.motion {
            Motion::On(c) => Some(c),
            Motion::Off => None,
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
        let Motion::On(c) = &mut self.motion else {
            return self.fault(id, Fault::NoMotion, tx);
        };
        // Every request is the host's heartbeat.
        c.heartbeat();
        let body = match apply(c, req) {
            Ok(()) => ReplyBody::Motion(MotionStatus::from(c.status())),
            Err(e) => ReplyBody::Fault(Fault::Motion(e)),
        };
        self.send(id, body, tx);
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
            let rates = Rates {
                insert_mm_s: driver.insert_speed,
                rotate_deg_s: driver.rotate_speed,
                spin_rev_s: driver.spin_rate,
            };
            c.set_job(rates, *needle_mm, driver.max_twist_deg)?;
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
