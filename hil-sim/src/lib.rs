//! A simulated needle-planner device: the very [`DeviceService`] the firmware runs, behind a line
//! that can corrupt and lose bytes and take the time a real UART takes.
//!
//! Use [`InProcess`] in tests (no threads, no clock), or [`serve`] on any byte stream (the
//! `hil-sim` binary serves a pseudo-terminal or a TCP socket).
//!
//! With [`SimulatedAxes`] (`hil-sim --axes`) the device drives simulated motors: its motion core
//! (protocol 10's motion requests) steps the simulated stages of `needle_motion::plant`.
//!
//! The device: the simulated robot, tissue and tracker of an insertion are the `needle-sim`
//! crate, which [`lab`] serves over OpenIGTLink as a tracker and a robot (`hil-sim --lab`).

#![forbid(unsafe_code)]

pub mod axes;
pub mod in_process;
pub mod lab;
pub mod line;
pub mod serve;

pub use axes::SimulatedAxes;
pub use in_process::{answer, AuditReport, InProcess};
pub use line::{FaultyLine, LineConfig, LineStats, Pacer};
pub use planner_core::device::{DeviceIdentity, DeviceService};
pub use serve::serve;

/// How the simulator introduces itself.
pub const IDENTITY: DeviceIdentity = DeviceIdentity {
    name: "hil-sim",
    firmware: env!("CARGO_PKG_VERSION"),
    build: concat!("host ", env!("CARGO_PKG_NAME")),
};
