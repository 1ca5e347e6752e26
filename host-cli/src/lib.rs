//! Host-side library behind the `needle` command: scenario files, plan rendering, commands,
//! simulated insertions, the benchmark on generated scenarios.

pub mod analysis;
pub mod anatomy;
pub mod bench;
pub mod benchmark;
pub mod device;
pub mod lab;
pub mod progress;
pub mod random;
pub mod report;
pub mod reserve;
pub mod scale;
pub mod scenario;
pub mod simulate;
