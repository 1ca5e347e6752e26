//! Talking to a planner device (hardware, QEMU or `hil-sim`) over a serial port or TCP.
//!
//! The protocol client and the transports are the `needle-link` crate (shared with
//! `needle device-bench`); [`commands`] backs `needle send`, `ping`, `info` and `ports`, and
//! [`verify`] re-checks the motor schedule a device sends with its plan.

pub mod commands;
pub mod verify;
