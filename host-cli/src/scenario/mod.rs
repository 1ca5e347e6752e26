//! The scenario model of the host: the TOML file format, polygon obstacles and the circles that
//! cover them, and the translation into the core's [`planner_core::Scenario`].
//!
//! Everything that reads a scenario (`plan`, `send`, the analysis commands) depends on this
//! module; it depends on none of them.

pub mod anatomy;
pub mod approx;
pub mod build;
mod exact;
pub mod execution;
pub mod file;
pub mod geometry;
pub mod label_clearance;
pub mod planted;
mod points;
pub mod polygon;
pub mod shapes;
pub mod steering;
pub mod unseen;
pub mod write;

pub use build::{load_scenario, load_scenario_shapes, parse_form, restrict};
pub use execution::{load_execution, load_plan_request, Execution, ExecutionMode};
pub use file::ScenarioFile;
pub use shapes::ObstacleShape;
