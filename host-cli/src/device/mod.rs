//! Talking to a planner device (hardware, QEMU or `hil-sim`) over a serial port or TCP.
//!
//! [`transport`] moves bytes with timeouts, [`client`] speaks the protocol of
//! [`planner_core::wire`] with explicit retries, and [`commands`] backs `needle send`, `ping`,
//! `info` and `ports`.

pub mod client;
pub mod commands;
pub mod transport;

pub use client::{Client, ClientConfig, LinkError, LinkStats, Progress};
pub use transport::{open, LinkTarget, Transport};
