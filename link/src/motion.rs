//! Motion on the device: one request (arm, home, move by a schedule's steps, hold, stop, e-stop,
//! clear a fault), answered with the motion core's status. A refusal comes back as
//! [`LinkError::Device`] with the motion core's reason (`Fault::Motion`), or `Fault::NoMotion`
//! from a device that drives no axes. Every request counts as the host's heartbeat.

use crate::client::Client;
use crate::error::LinkError;
use crate::transport::Transport;
use planner_core::wire::{MotionRequest, MotionStatus, ReplyBody, RequestBody};

impl<T: Transport> Client<T> {
    /// Sends `request` to the motion core; its status after the request. A `Move` is sent once,
    /// whatever the retry policy: a repeat after a lost answer would find the core moving and be
    /// refused, so after a lost answer the caller reads the status instead. Every other request
    /// changes nothing when repeated and is resent as any request is.
    pub fn motion(&mut self, request: MotionRequest) -> Result<MotionStatus, LinkError> {
        self.begin();
        let id = self.new_id();
        let retries = self.config.retries;
        if matches!(request, MotionRequest::Move { .. }) {
            self.config.retries = 0;
        }
        let answer = self.exchange("motion", id, &RequestBody::Motion(request), |b| match b {
            ReplyBody::Motion(s) => Some(*s),
            _ => None,
        });
        self.config.retries = retries;
        answer
    }
}
