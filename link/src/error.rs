//! Why talking to the device failed, with what was tried and what came back, every figure
//! measured.

use planner_core::wire::{Fault, PROTOCOL_VERSION};
use std::fmt;
use std::io;
use std::time::Duration;

/// Why an exchange stopped trying.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GaveUp {
    /// The device sent no frame at all (intact or damaged) for this long: the `timeout`.
    Silence {
        /// The silence allowed.
        allowed: Duration,
    },
    /// The request was sent as often as allowed and the last attempt's wait ran out too.
    Retries {
        /// Repeats allowed.
        limit: u32,
    },
    /// The whole operation's deadline passed.
    Deadline {
        /// The deadline, from the start of the operation.
        limit: Duration,
    },
}

/// What one exchange tried and what came back (all counted or measured, none assumed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tries {
    /// Times the request was sent.
    pub sent: u32,
    /// From the first send to giving up.
    pub elapsed: Duration,
    /// Frames that arrived damaged (CRC, stuffing or decoding).
    pub damaged: u32,
    /// Reports from the device that a frame reached it damaged.
    pub line_faults: u32,
    /// Intact replies to earlier requests or attempts, dropped.
    pub stale: u32,
    /// Silence at the end: time since the last frame (or the first send).
    pub silence: Duration,
}

/// Why talking to the device failed.
#[derive(Debug)]
pub enum LinkError {
    /// The port or socket failed (opening it, or before any request).
    Io(io::Error),
    /// The port or socket failed in the middle of an exchange.
    Lost {
        /// What was asked.
        what: &'static str,
        /// Time from the start of the operation.
        after: Duration,
        /// The transport's error.
        error: io::Error,
    },
    /// No usable answer.
    NoAnswer {
        /// What was asked.
        what: &'static str,
        /// Upload or fetch offset, if the request has one.
        offset: Option<u16>,
        /// What was tried and what came back.
        tries: Tries,
        /// Why it stopped.
        why: GaveUp,
    },
    /// The device stayed silent while planning for longer than the client waits without asking
    /// (see [`Client::with_quiet_planning`](crate::Client::with_quiet_planning)).
    NoResult {
        /// The longest silence allowed.
        waited: Duration,
    },
    /// The device kept planning past the operation's deadline.
    PlanTooLong {
        /// Forms done and forms in all, as last reported.
        done: (u8, u8),
        /// Time from the start of the plan.
        after: Duration,
        /// The deadline.
        limit: Duration,
    },
    /// The device refused the request.
    Device(Fault),
    /// The device speaks another protocol version.
    Version {
        /// The device's.
        device: u8,
    },
    /// The plan (or a long steering answer) came back damaged every time, or did not decode.
    CorruptResult,
}

fn secs(d: Duration) -> String {
    format!("{:.2} s", d.as_secs_f64())
}

fn plural(n: u32, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

impl fmt::Display for Tries {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "sent {} in {}; came back: {}, {} reported by the device, {} dropped; \
             then {} of silence",
            plural(self.sent, "time", "times"),
            secs(self.elapsed),
            plural(self.damaged, "damaged frame", "damaged frames"),
            plural(self.line_faults, "damaged request", "damaged requests"),
            plural(self.stale, "stale reply", "stale replies"),
            secs(self.silence),
        )
    }
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::Io(e) => write!(f, "link failed: {e}"),
            LinkError::Lost { what, after, error } => write!(
                f,
                "the link failed during the {what} ({} into the operation): {error}",
                secs(*after)
            ),
            LinkError::NoAnswer {
                what,
                offset,
                tries,
                why,
            } => {
                write!(f, "the device did not answer the {what}")?;
                if let Some(o) = offset {
                    write!(f, " at offset {o}")?;
                }
                write!(f, " ({tries}); ")?;
                match why {
                    GaveUp::Silence { allowed } => {
                        write!(f, "gave up after {} of silence (--timeout)", secs(*allowed))
                    }
                    GaveUp::Retries { limit } => {
                        write!(f, "gave up after {limit} repeats (--retries)")
                    }
                    GaveUp::Deadline { limit } => {
                        write!(f, "gave up at the {} deadline (--deadline)", secs(*limit))
                    }
                }
            }
            LinkError::NoResult { waited } => write!(
                f,
                "the device sent nothing for {} while planning",
                secs(*waited)
            ),
            LinkError::PlanTooLong { done, after, limit } => write!(
                f,
                "the device was still planning after {} ({} of {} forms done): past the {} \
                 deadline (--deadline)",
                secs(*after),
                done.0,
                done.1,
                secs(*limit)
            ),
            LinkError::Device(Fault::Internal) => f.write_str(
                "the device hit an internal error and is restarting; the request was lost \
                 (a firmware bug: please report it with the device's log)",
            ),
            LinkError::Device(Fault::UnknownRequest) => f.write_str(
                "the device no longer knows this request (it restarted and lost it, or \
                 another client replaced it)",
            ),
            LinkError::Device(fault) => write!(f, "the device refused the request: {fault:?}"),
            LinkError::Version { device } => write!(
                f,
                "the device speaks protocol version {device}, this needle speaks {PROTOCOL_VERSION}"
            ),
            LinkError::CorruptResult => f.write_str(
                "the answer fetched in parts arrived damaged on every attempt (CRC mismatch)",
            ),
        }
    }
}

impl std::error::Error for LinkError {}

impl From<io::Error> for LinkError {
    fn from(e: io::Error) -> Self {
        LinkError::Io(e)
    }
}

/// An encoding failure on this side (a request over the protocol's bounds) as a link error.
pub(crate) fn too_large(what: &str) -> LinkError {
    LinkError::Io(io::Error::other(what.to_owned()))
}
