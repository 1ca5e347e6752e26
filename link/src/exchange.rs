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
use std::time::{Duration, Instant};

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

/// Where one exchange stands. Each state is handled by one method of the client, which returns
/// the next state.
enum State<R> {
    /// The request is to be sent (again).
    Send,
    /// An attempt is out; the next event decides.
    Wait(Attempt),
    /// `accept` took an answer.
    Answered(R),
    /// No answer will come.
    GaveUp(GaveUp),
}

/// One attempt in flight.
#[derive(Clone, Copy)]
struct Attempt {
    sent_at: Instant,
    /// When a silent attempt is sent again (for the last attempt: when it is given up).
    resend_at: Instant,
    /// Whether another attempt may follow this one.
    may_resend: bool,
}

/// What one exchange has seen so far: its waits are measured from it and its error reports it.
struct Progress {
    what: &'static str,
    id: u16,
    start: Instant,
    tries: Tries,
    last_heard: Instant,
    /// Silent attempts in a row (the resend interval grows with each).
    silent: u32,
}

impl Progress {
    fn no_answer(mut self, offset: Option<u16>, why: GaveUp) -> LinkError {
        let now = Instant::now();
        self.tries.elapsed = now - self.start;
        self.tries.silence = now - self.last_heard;
        LinkError::NoAnswer {
            what: self.what,
            offset,
            tries: self.tries,
            why,
        }
    }
}

/// The bounds of one wait: it ends at `limit`, the earliest of the silence budget's end, the
/// attempt's `resend_at` and the operation's deadline; which one it was decides what follows.
struct WaitBounds {
    limit: Instant,
    /// The silence budget's end.
    silence_end: Instant,
    /// The operation's deadline and the duration it was given.
    deadline: Option<(Instant, Duration)>,
}

/// A damaged frame the device says it got (for this request or an earlier one): the device is
/// alive, the request is worth sending again at once.
fn reports_line_fault(reply: &Reply) -> bool {
    match reply.body {
        ReplyBody::Fault(f) => {
            is_line_fault(f) && (reply.header.id == 0 || f == Fault::Undecodable)
        }
        _ => false,
    }
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
        let mut progress = Progress {
            what,
            id,
            start,
            tries: Tries::default(),
            last_heard: start,
            silent: 0,
        };
        let mut state = State::Send;
        loop {
            state = match state {
                State::Send => State::Wait(self.send_attempt(&mut progress, &mut make)?),
                State::Wait(attempt) => self.on_next_event(&mut progress, attempt, accept)?,
                State::Answered(r) => return Ok(r),
                State::GaveUp(why) => return Err(progress.no_answer(offset, why)),
            };
        }
    }

    /// Sends one attempt; a repeat halves the chunk first.
    fn send_attempt(
        &mut self,
        p: &mut Progress,
        make: &mut dyn FnMut(usize) -> RequestBody,
    ) -> Result<Attempt, LinkError> {
        if p.tries.sent > 0 {
            self.stats.retried += 1;
            self.chunk = (self.chunk / 2).max(MIN_CHUNK);
        }
        let body = make(self.chunk);
        let sent_at = Instant::now();
        self.send(p.id, &body)
            .map_err(|e| self.lost_if_io(p.what, e))?;
        p.tries.sent += 1;
        let may_resend = p.tries.sent <= self.config.retries;
        // The last attempt waits its full `timeout`, a silent one its resend interval.
        let resend_at = if may_resend {
            sent_at + self.resend_interval(p.silent)
        } else {
            sent_at + self.config.timeout
        };
        Ok(Attempt {
            sent_at,
            resend_at,
            may_resend,
        })
    }

    /// Waits for the next event of an attempt: silence, a damaged frame, or a reply.
    fn on_next_event<R>(
        &mut self,
        p: &mut Progress,
        attempt: Attempt,
        accept: &mut dyn FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<State<R>, LinkError> {
        let silence_end = p.last_heard + self.config.timeout;
        let deadline = self.deadline();
        let mut limit = silence_end.min(attempt.resend_at);
        if let Some((end, _)) = deadline {
            limit = limit.min(end);
        }
        let event = self
            .next_event(limit)
            .map_err(|e| self.lost_if_io(p.what, e))?;
        let now = Instant::now();
        let reply = match event {
            None => {
                let bounds = WaitBounds {
                    limit,
                    silence_end,
                    deadline,
                };
                return Ok(self.on_silence(p, attempt, &bounds));
            }
            Some(Event::Damaged) => None,
            Some(Event::Reply(r)) => Some(*r),
        };
        p.last_heard = now;
        match reply {
            Some(reply) if !reports_line_fault(&reply) => {
                self.on_reply(p, attempt, &reply, now, accept)
            }
            damaged_or_line_fault => {
                if damaged_or_line_fault.is_some() {
                    p.tries.line_faults += 1;
                } else {
                    p.tries.damaged += 1;
                }
                self.stats.detected += 1;
                p.silent = 0;
                Ok(if attempt.may_resend {
                    State::Send
                } else {
                    State::Wait(attempt)
                })
            }
        }
    }

    /// The wait ran to its limit (a transport may report silence early: in-process silence
    /// costs no time); which bound it was decides.
    fn on_silence<R>(&mut self, p: &mut Progress, attempt: Attempt, b: &WaitBounds) -> State<R> {
        self.stats.timeouts += 1;
        if let Some((_, allowed)) = b.deadline.filter(|(end, _)| b.limit == *end) {
            return State::GaveUp(GaveUp::Deadline { limit: allowed });
        }
        if b.limit == b.silence_end {
            return State::GaveUp(GaveUp::Silence {
                allowed: self.config.timeout,
            });
        }
        if !attempt.may_resend {
            return State::GaveUp(GaveUp::Retries {
                limit: self.config.retries,
            });
        }
        p.silent += 1;
        State::Send
    }

    /// An intact reply: an answer `accept` takes, an error of the device, or a stale reply.
    fn on_reply<R>(
        &mut self,
        p: &mut Progress,
        attempt: Attempt,
        reply: &Reply,
        now: Instant,
        accept: &mut dyn FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<State<R>, LinkError> {
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
        if reply.header.id == p.id {
            if let Some(r) = accept(&reply.body) {
                if p.tries.sent == 1 {
                    // Karn's rule: only an unambiguous answer measures the round trip.
                    self.sample_rtt(now - attempt.sent_at);
                }
                self.chunk = (self.chunk + MIN_CHUNK).min(self.max_chunk);
                return Ok(State::Answered(r));
            }
            match reply.body {
                ReplyBody::Fault(f) => return Err(LinkError::Device(f)),
                ReplyBody::Finished { len, crc } => {
                    self.finished = Some((p.id, len, crc));
                    return Ok(State::Wait(attempt));
                }
                _ => {}
            }
        }
        p.tries.stale += 1;
        self.stats.stale += 1;
        Ok(State::Wait(attempt))
    }

    /// A transport failure met during `what` becomes [`LinkError::Lost`]; other errors pass.
    fn lost_if_io(&self, what: &'static str, error: LinkError) -> LinkError {
        match error {
            LinkError::Io(e) => self.lost(what, e),
            e => e,
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
