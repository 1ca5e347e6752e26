//! What a plan is, as `needle` shows it: the typed JSON report of `needle plan --json` (which
//! `needle send --json` prints too, and `needle plot --plan` reads back), the human-readable
//! table, and the report of a weight sweep.
//!
//! `needle send` prints through the same functions, so a plan from a device reads exactly like a
//! local one.

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
