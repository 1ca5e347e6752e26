//! What a plan is, as `needle` shows it: the typed JSON report of `needle plan --json` (which
//! `needle send --json` prints too, and `needle plot --plan` reads back), the human-readable
//! table, and the report of a weight sweep.
//!
//! `needle send` prints through the same functions, so a plan from a device reads exactly like a
//! local one; [`slicer`] writes the files 3D Slicer opens (`--export`).
//!
//! Planning a scenario as `needle plan` does and printing its table and schedule:
//!
//! ```
//! use needle_report::local::plan_locally;
//! use needle_report::schedule_table;
//! use std::path::Path;
//!
//! let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/paper.toml");
//! let scenario = needle_scenario::load_scenario(&file)?;
//! let execution = needle_scenario::load_execution(&file)?;
//! let made = plan_locally(&scenario, &execution)?;
//! made.verdict()?; // a plan the command would print without an error
//! let best = made.report().best().expect("a path");
//! assert!(made.table(&execution).contains(&best.form.to_string()));
//! let schedule = made.schedule()?.expect("the best path is scheduled");
//! assert!(!schedule_table(schedule, &made.scenario.driver).is_empty());
//! # Ok::<(), anyhow::Error>(())
//! ```

pub mod execution;
pub mod json;
pub mod local;
pub mod schedule;
pub mod slicer;
pub mod sweep;
pub mod table;

pub use json::{finite, path_points, plan_json, PlanJson, Stats};
pub use schedule::{schedule_table, ScheduleJson};
pub use table::plan_table;
