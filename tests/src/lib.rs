//! End-to-end tests live in `tests/`; this crate also holds the independent reference planner
//! that the optimality tests compare `planner-core` against.

pub mod reference;
