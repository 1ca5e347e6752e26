//! Developer tooling of needle-planner, kept out of the `needle` binary: what the firmware costs
//! on the microcontroller ([`device_bench`], run as `cargo xtask device-bench`; the [`figures`]
//! it measures) and what it may cost ([`budgets`]), the QEMU run it drives ([`qemu`]) and a debugger's write into it ([`gdb_remote`]), reading
//! the firmware image ([`elf`], with the `object` and `rustc-demangle` crates), the steering
//! readings' and the step interrupt's counts ([`replan_bench`], [`step_bench`]), where the counted
//! instructions go ([`profile`]), and the firmware and plugin builds that device-bench and the
//! `firmware_*` tests share ([`firmware_artifacts`]).
//!
//! The crates, without a cycle:
//!
//! ```text
//! xtask (`cargo xtask`) ──> needle-devtools ──> needle-link ──> planner-core
//!       └─────────────────> needle-scenario
//! ```
//!
//! This crate reads no scenario file itself: the one thing device-bench needs of the host's
//! crates, reading scenario files with their collision bound, is passed in by the caller
//! ([`device_bench::run`]; the xtask passes `needle-scenario`'s reader), so the tooling stays
//! below the host crates and none of them, nor the `needle` binary, depends on it.

#![deny(missing_docs)]

pub mod budgets;
pub mod device_bench;
pub mod elf;
pub mod figures;
pub mod firmware_artifacts;
pub mod gdb_remote;
pub mod profile;
pub mod qemu;
pub mod replan_bench;
pub mod step_bench;
