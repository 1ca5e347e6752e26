//! One request until it is answered: the client's retry policy.

use crate::client::{Client, Event, MIN_CHUNK};
use crate::error::LinkError;
use crate::transport::Transport;
use planner_core::wire::{Fault, Reply, ReplyBody, RequestBody, PROTOCOL_VERSION};
use std::time::Instant;

/// Faults the device reports about frames it could not read: the request is worth resending.
pub(crate) fn is_line_fault(f: Fault) -> bool {
    matches!(
        f,
        Fault::BadCrc
            | Fault::Truncated
            | Fault::FrameTooLong
            | Fault::Overrun
            | Fault::Undecodable
    )
}

impl<T: Transport> Client<T> {
    /// The next reply (damaged frames counted and skipped), for tests of malformed input.
    pub fn next_reply(&mut self) -> Result<Option<Reply>, LinkError> {
        let deadline = Instant::now() + self.config.timeout;
        loop {
            match self.next_event(deadline)? {
                None => return Ok(None),
                Some(Event::Damaged) => self.stats.detected += 1,
                Some(Event::Reply(r)) => return Ok(Some(*r)),
            }
        }
    }

    /// Sends `body` until `accept` takes an answer to request `id`.
    pub(crate) fn exchange<R>(
        &mut self,
        what: &'static str,
        id: u16,
        body: &RequestBody,
        mut accept: impl FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<R, LinkError> {
        self.exchange_with(what, id, |_| body.clone(), &mut accept)
    }

    /// Like `exchange`, but the body is rebuilt for each attempt from the current chunk size,
    /// which halves after every failed attempt and grows back after every answered one.
    pub(crate) fn exchange_with<R>(
        &mut self,
        what: &'static str,
        id: u16,
        mut make: impl FnMut(usize) -> RequestBody,
        accept: &mut dyn FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<R, LinkError> {
        for attempt in 0..=self.config.retries {
            if attempt > 0 {
                self.stats.retried += 1;
                self.chunk = (self.chunk / 2).max(MIN_CHUNK);
            }
            let body = make(self.chunk);
            if let Some(r) = self.attempt(id, &body, accept)? {
                self.chunk = (self.chunk + MIN_CHUNK).min(self.max_chunk);
                return Ok(r);
            }
        }
        Err(LinkError::NoAnswer {
            what,
            attempts: self.config.retries + 1,
            timeout: self.config.timeout,
        })
    }

    /// Sends `body` once and waits for an answer; `None` after silence or a damaged frame.
    fn attempt<R>(
        &mut self,
        id: u16,
        body: &RequestBody,
        accept: &mut dyn FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<Option<R>, LinkError> {
        self.send(id, body)?;
        let deadline = Instant::now() + self.config.timeout;
        loop {
            let reply = match self.next_event(deadline)? {
                None => {
                    self.stats.timeouts += 1;
                    return Ok(None);
                }
                Some(Event::Damaged) => {
                    self.stats.detected += 1;
                    return Ok(None);
                }
                Some(Event::Reply(r)) => *r,
            };
            if let ReplyBody::Fault(Fault::UnsupportedVersion { supported, .. }) = reply.body {
                return Err(LinkError::Version { device: supported });
            }
            if reply.header.version != PROTOCOL_VERSION {
                return Err(LinkError::Version {
                    device: reply.header.version,
                });
            }
            if reply.body == ReplyBody::Fault(Fault::Internal) {
                return Err(LinkError::Device(Fault::Internal));
            }
            if let ReplyBody::Fault(f) = reply.body {
                if is_line_fault(f) && (reply.header.id == 0 || f == Fault::Undecodable) {
                    // The device saw a damaged frame, most likely this request.
                    self.stats.detected += 1;
                    return Ok(None);
                }
            }
            if reply.header.id != id {
                continue;
            }
            if let Some(r) = accept(&reply.body) {
                return Ok(Some(r));
            }
            match reply.body {
                ReplyBody::Fault(f) => return Err(LinkError::Device(f)),
                ReplyBody::Finished { len, crc } => self.finished = Some((id, len, crc)),
                _ => {}
            }
        }
    }
}
