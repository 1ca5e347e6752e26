//! Talking to a planner device (hardware, QEMU or `hil-sim`) over a serial port or TCP.
//!
//! The protocol client and the transports are the `needle-link` crate (shared with
//! `needle device-bench`); [`commands`] backs `needle send`, `ping`, `info` and `ports`.

pub mod commands;
