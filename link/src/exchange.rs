//! One request until it is answered: the client's retry policy.
//!
//! - A damaged frame (caught by the CRC here, or a line fault the device reports) is answered
//!   by sending the request again at once: the device is alive and the line carries frames.
//! - Silence is answered by sending the request again after a resend interval adapted to the
//!   measured round trip (see [`Client::resend_interval`]), doubling while the silence lasts:
//!   a reply whose closing delimiter was lost only ends when another frame arrives.
//! - An exchange fails when the device has sent no frame at all for `timeout` (the silence
//!   budget: damaged frames do not use it up), when the request has been repeated `retries`
//!   times and the last attempt's wait ran out too, or at the operation's deadline.
//! - Replies are matched to the request by id and, through `accept`, by offset: intact replies
//!   to an earlier request or attempt are dropped and counted (`LinkStats::stale`), never
//!   taken for an answer and never counted as failures.

use crate::client::{Client, Event, MIN_CHUNK};
use crate::error::{GaveUp, LinkError, Tries};
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

/// What ended one wait.
enum Next {
    /// Send the request again.
    Resend,
    /// Stop trying.
    GiveUp(GaveUp),
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
        self.exchange_with(what, None, id, |_| body.clone(), &mut accept)
    }

    /// Like `exchange`, but the body is rebuilt for each attempt from the current chunk size,
    /// which halves after every failed attempt and grows back after every answered one.
    /// `offset` only names the request in an error; `accept` matches it.
    pub(crate) fn exchange_with<R>(
        &mut self,
        what: &'static str,
        offset: Option<u16>,
        id: u16,
        mut make: impl FnMut(usize) -> RequestBody,
        accept: &mut dyn FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<R, LinkError> {
        let start = Instant::now();
        let mut tries = Tries::default();
        let mut last_heard = start;
        let mut silent = 0u32;
        loop {
            if tries.sent > 0 {
                self.stats.retried += 1;
                self.chunk = (self.chunk / 2).max(MIN_CHUNK);
            }
            let body = make(self.chunk);
            let sent_at = Instant::now();
            match self.send(id, &body) {
                Ok(()) => {}
                Err(LinkError::Io(e)) => return Err(self.lost(what, e)),
                Err(e) => return Err(e),
            }
            tries.sent += 1;
            let may_resend = tries.sent <= self.config.retries;
            // The last attempt waits its full `timeout`, a silent one its resend interval.
            let resend_at = if may_resend {
                sent_at + self.resend_interval(silent)
            } else {
                sent_at + self.config.timeout
            };
            let next = loop {
                let silence_end = last_heard + self.config.timeout;
                let deadline = self.deadline();
                let mut limit = silence_end.min(resend_at);
                if let Some((end, _)) = deadline {
                    limit = limit.min(end);
                }
                let event = match self.next_event(limit) {
                    Ok(e) => e,
                    Err(LinkError::Io(e)) => return Err(self.lost(what, e)),
                    Err(e) => return Err(e),
                };
                let now = Instant::now();
                let reply = match event {
                    // The wait ran to `limit` (a transport may report silence early: in-process
                    // silence costs no time); which bound it was decides.
                    None => {
                        self.stats.timeouts += 1;
                        if deadline.is_some_and(|(end, _)| limit == end) {
                            let limit = deadline.map(|(_, d)| d).unwrap_or_default();
                            break Next::GiveUp(GaveUp::Deadline { limit });
                        }
                        if limit == silence_end {
                            break Next::GiveUp(GaveUp::Silence {
                                allowed: self.config.timeout,
                            });
                        }
                        if !may_resend {
                            let limit = self.config.retries;
                            break Next::GiveUp(GaveUp::Retries { limit });
                        }
                        silent += 1;
                        break Next::Resend;
                    }
                    Some(Event::Damaged) => None,
                    Some(Event::Reply(r)) => Some(*r),
                };
                last_heard = now;
                // A damaged frame, or the device saying it got one (this request or an earlier
                // one): the device is alive, the request is worth sending again at once.
                let line_fault = reply.as_ref().is_some_and(|r| match r.body {
                    ReplyBody::Fault(f) => {
                        is_line_fault(f) && (r.header.id == 0 || f == Fault::Undecodable)
                    }
                    _ => false,
                });
                let Some(reply) = reply.filter(|_| !line_fault) else {
                    if line_fault {
                        tries.line_faults += 1;
                    } else {
                        tries.damaged += 1;
                    }
                    self.stats.detected += 1;
                    silent = 0;
                    if may_resend {
                        break Next::Resend;
                    }
                    continue;
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
                if reply.header.id == id {
                    if let Some(r) = accept(&reply.body) {
                        if tries.sent == 1 {
                            // Karn's rule: only an unambiguous answer measures the round trip.
                            self.sample_rtt(now - sent_at);
                        }
                        self.chunk = (self.chunk + MIN_CHUNK).min(self.max_chunk);
                        return Ok(r);
                    }
                    match reply.body {
                        ReplyBody::Fault(f) => return Err(LinkError::Device(f)),
                        ReplyBody::Finished { len, crc } => {
                            self.finished = Some((id, len, crc));
                            continue;
                        }
                        _ => {}
                    }
                }
                tries.stale += 1;
                self.stats.stale += 1;
            };
            if let Next::GiveUp(why) = next {
                let now = Instant::now();
                tries.elapsed = now - start;
                tries.silence = now - last_heard;
                return Err(LinkError::NoAnswer {
                    what,
                    offset,
                    tries,
                    why,
                });
            }
        }
    }

    /// A transport failure in the middle of `what`.
    pub(crate) fn lost(&self, what: &'static str, error: std::io::Error) -> LinkError {
        LinkError::Lost {
            what,
            after: self.op_start.elapsed(),
            error,
        }
    }
}
