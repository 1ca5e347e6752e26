//! The scenario model of the host: the TOML file format (docs/scenario.md) and its validation,
//! polygon obstacles and the circles that cover them, `[[anatomy]]` label maps covered through
//! `needle-anatomy`, the `[execution]` and `[steering]` tables, the seeded families of generated
//! scenarios ([`unseen`], [`planted`]), and the translation into the core's
//! [`planner_core::Scenario`]; with [`reserve`], the one rule for the curvature reserve a plan
//! keeps.
//!
//! Everything that reads a scenario (`needle plan`, `send`, the analyses, the lab, the Python
//! package) depends on this crate; it depends on none of them.
//!
//! Loading a scenario file and planning it, the first thing most callers do:
//!
//! ```
//! use std::path::Path;
//!
//! let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/paper.toml");
//! let scenario = needle_scenario::load_scenario(&file)?;
//! let report = planner_core::plan(&scenario)?;
//! let best = report.best().expect("the paper's scenario has a path");
//! assert!(best.feasible);
//! // The same scenario written as text plans the same.
//! let text = std::fs::read_to_string(&file)?;
//! let again = needle_scenario::ScenarioFile::parse(&text)?.to_scenario()?;
//! assert_eq!(planner_core::plan(&again)?.best(), Some(best));
//! # Ok::<(), anyhow::Error>(())
//! ```

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
pub mod reserve;
pub mod shapes;
pub mod steering;
pub mod unseen;
pub mod voxels;
pub mod write;

pub use build::{load_plan_request, load_scenario, load_scenario_shapes, parse_form, restrict};
pub use execution::{load_execution, Execution, ExecutionMode};
pub use file::ScenarioFile;
pub use shapes::ObstacleShape;
