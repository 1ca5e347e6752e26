//! The host side of the needle-planner device protocol ([`planner_core::wire`]): byte transports
//! (serial port, TCP) and the one protocol client, used by `needle send|ping|info` and by
//! `cargo xtask device-bench`.
//!
//! It is a crate of its own so that both users can depend on it without a cycle: `needle-cli`
//! (the `needle` command) depends on `needle-devtools` (device-bench) to run its subcommand, and
//! both depend on this crate; it depends on `planner-core` alone.
//!
//! The modules, by concern: [`transport`] moves bytes with timeouts; `client` holds the session
//! state and turns bytes into frames; `exchange` sends one request until it is answered (the
//! retry policy); `hello` (greeting, ping, cancel), `upload`, `plan` (waiting while the device
//! plans), `fetch` and `motion` (the board's axes) are the requests built on it. [`LinkError`] says why a session failed.

#![deny(missing_docs)]

mod client;
mod error;
mod exchange;
mod fetch;
mod hello;
mod motion;
mod plan;
mod steer;
pub mod transport;
mod upload;

pub use client::{Client, ClientConfig, LinkStats};
pub use error::{GaveUp, LinkError, Tries};
pub use plan::Progress;
pub use transport::{open, tcp, LinkTarget, Transport};
