//! Talking to a planner device (hardware, QEMU or `hil-sim`) over a serial port or TCP.
//!
//! The protocol client and the transports are the `needle-link` crate (shared with
//! `cargo xtask device-bench`); [`commands`] reaches the device ([`LinkOptions`]) and backs
//! `needle ping`, `info` and `ports`, [`send`] runs a whole plan within `--deadline` (starting over when the device
//! restarts), [`verify`] re-checks the motor schedule a device sends with its plan and its
//! figures under a collision bound, and [`checked`] puts the two together. [`motion`] moves the
//! board's axes (`needle motion`).
//!
//! Planning a scenario on a device, checked, as `needle send` does (here `hil-sim --tcp
//! 127.0.0.1:7878`, started first):
//!
//! ```no_run
//! use needle_device::checked::{plan_checked, Sent};
//! use needle_device::LinkOptions;
//!
//! let link = LinkOptions { tcp: Some("127.0.0.1:7878".into()), ..LinkOptions::default() };
//! let file = std::path::Path::new("examples/paper.toml");
//! let scenario = needle_scenario::load_scenario(file)?;
//! let execution = needle_scenario::load_execution(file)?;
//! match plan_checked(&scenario, &execution, &link)? {
//!     Sent::Planned(made) => print!("{}", made.table(&execution)),
//!     Sent::Refused(why) => eprintln!("the device refused the scenario: {why:#}"),
//! }
//! # Ok::<(), anyhow::Error>(())
//! ```

pub mod checked;
pub mod commands;
pub mod motion;
pub mod posture;
pub mod send;
pub mod verify;

pub use commands::LinkOptions;
