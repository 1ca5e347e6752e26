//! Motion on the device: one request (arm, home, move by a schedule's steps, hold, stop, e-stop,
//! clear a fault), answered with the motion core's status. A refusal comes back as
//! [`LinkError::Device`] with the motion core's reason (`Fault::Motion`), or `Fault::NoMotion`
//! from a device that drives no axes. Every request counts as the host's heartbeat. A `Move` is
//! not safe to resend (a repeat finds the core moving and is refused): give the client no
//! retries for motion, and read the status after a lost answer.

use crate::client::Client;
use crate::error::LinkError;
use crate::transport::Transport;
use planner_core::wire::{MotionRequest, MotionStatus, ReplyBody, RequestBody};

impl<T: Transport> Client<T> {
    /// Sends `request` to the motion core; its status after the request.
    pub fn motion(&mut self, request: MotionRequest) -> Result<MotionStatus, LinkError> {
        self.begin();
        let id = self.new_id();
        self.exchange("motion", id, &RequestBody::Motion(request), |b| match b {
            ReplyBody::Motion(s) => Some(*s),
            _ => None,
        })
    }
}
