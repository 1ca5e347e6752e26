//! Host-side library behind the `needle` command: scenario files, plan rendering, commands.

pub mod analysis;
pub mod bench;
pub mod device;
pub mod firmware_artifacts;
pub mod random;
pub mod report;
pub mod scenario;

/// The scenario module's old name: `device_bench.rs` and the firmware tests still load scenarios
/// through it; drop it once they import [`scenario`] (they are being moved by another change).
pub use scenario as scenario_file;
