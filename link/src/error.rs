//! Why talking to the device failed.

use planner_core::wire::{Fault, PROTOCOL_VERSION};
use std::fmt;
use std::io;
use std::time::Duration;

/// Why talking to the device failed.
#[derive(Debug)]
pub enum LinkError {
    /// The port or socket failed.
    Io(io::Error),
    /// No usable answer after every retry.
    NoAnswer {
        /// What was asked.
        what: &'static str,
        /// Times it was sent.
        attempts: u32,
        /// Wait after each.
        timeout: Duration,
    },
    /// The device stayed silent while planning for longer than the client waits without asking
    /// (see [`Client::with_quiet_planning`](crate::Client::with_quiet_planning)).
    NoResult {
        /// The longest silence allowed.
        waited: Duration,
    },
    /// The device refused the request.
    Device(Fault),
    /// The device speaks another protocol version.
    Version {
        /// The device's.
        device: u8,
    },
    /// The plan came back damaged every time, or did not decode.
    CorruptResult,
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::Io(e) => write!(f, "link failed: {e}"),
            LinkError::NoAnswer {
                what,
                attempts,
                timeout,
            } => write!(
                f,
                "the device did not answer ({what}: {attempts} attempts, {:.1} s each)",
                timeout.as_secs_f64()
            ),
            LinkError::NoResult { waited } => write!(
                f,
                "the device sent nothing for {:.1} s while planning",
                waited.as_secs_f64()
            ),
            LinkError::Device(Fault::Internal) => f.write_str(
                "the device hit an internal error and is restarting; the request was lost \
                 (a firmware bug: please report it with the device's log)",
            ),
            LinkError::Device(fault) => write!(f, "the device refused the request: {fault:?}"),
            LinkError::Version { device } => write!(
                f,
                "the device speaks protocol version {device}, this needle speaks {PROTOCOL_VERSION}"
            ),
            LinkError::CorruptResult => {
                f.write_str("the plan arrived damaged on every attempt (CRC mismatch)")
            }
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
