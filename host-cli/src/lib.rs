//! Host-side library behind the `needle` command: scenario files, plan rendering, commands,
//! simulated insertions.

pub mod analysis;
pub mod bench;
pub mod device;
pub mod random;
pub mod report;
pub mod scenario;
pub mod simulate;
