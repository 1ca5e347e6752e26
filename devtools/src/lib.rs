//! Developer tooling of needle-planner, kept out of the `needle` command's own code: what the
//! firmware costs on the microcontroller ([`device_bench`], run as `needle device-bench`; the
//! [`figures`] it measures) and what it may cost ([`budgets`]), the QEMU run it drives
//! ([`qemu`]), reading the firmware image ([`elf`], with the `object` and `rustc-demangle` crates), where the counted instructions go ([`profile`]), and the firmware
//! and plugin builds that device-bench and the `firmware_*` tests share
//! ([`firmware_artifacts`]).
//!
//! The crates, without a cycle:
//!
//! ```text
//! needle-cli (the `needle` command) ──> needle-devtools ──> needle-link ──> planner-core
//!            └──────────────────────────────────────────> needle-link
//! ```
//!
//! `needle device-bench` must keep working, so `needle-cli` depends on this crate; this crate
//! therefore cannot depend on `needle-cli`. What both need, the device client and its
//! transports, is `needle-link`, below both. The one thing of `needle-cli`'s that device-bench
//! uses, reading scenario files, is passed in by the caller ([`device_bench::run`]). It is a
//! library and not an xtask binary for the same reason: its front end is `needle`.

#![deny(missing_docs)]

pub mod budgets;
pub mod device_bench;
pub mod elf;
pub mod figures;
pub mod firmware_artifacts;
pub mod profile;
pub mod qemu;
pub mod replan_bench;
