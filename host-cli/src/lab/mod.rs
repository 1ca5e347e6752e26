//! The lab link: `needle steer` steering an insertion from an OpenIGTLink tracker stream and
//! commanding a robot, and what the simulated lab (`hil-sim --lab`) shares with it.

pub mod fresh;
pub mod log;
pub mod outcome;
pub mod progress;
pub mod report;
pub mod robot;
pub mod session;
pub mod slicer;
pub mod sphere;
pub mod steer;
pub mod tracker;
pub mod viewers;
pub mod wire;

pub use outcome::exit_code;
pub use steer::{run_steer, SteerArgs};
