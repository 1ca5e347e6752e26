//! Talking to a planner device (hardware, QEMU or `hil-sim`) over a serial port or TCP.
//!
//! The protocol client and the transports are the `needle-link` crate (shared with
//! `needle device-bench`); [`commands`] reaches the device and backs `needle ping`, `info` and
//! `ports`, [`send`] runs a whole plan within `--deadline` (starting over when the device
//! restarts), [`verify`] re-checks the motor schedule a device sends with its plan and its
//! figures under a collision bound, and [`checked`] puts the two together.

pub mod checked;
pub mod commands;
pub mod send;
pub mod verify;
