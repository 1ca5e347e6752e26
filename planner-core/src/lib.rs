//! Path planner for bevel-tip steerable needles: `no_std`, no heap, bounded work.
//!
//! Data flows scenario → forms → solve → check → report → frame, one module or folder each:
//! a [`Scenario`] ([`model`]) is validated; every [`Form`] is solved by the global search
//! (`search`: closed-form seeds, then the feasible-path SQP of `optim` over the insertion posture
//! and the segment parameters); every candidate is re-measured by [`check`] independently of the
//! optimiser and becomes a [`FormOutcome`] of the [`PlanReport`] ([`report`]); a [`PlanSession`]
//! ([`session`]) plans form by form and keeps the best; [`wire`] carries requests and reports
//! in checked frames and [`device`] is the request handler a board runs. During an insertion
//! the closed loop ([`steer`]) re-plans the rest of the path from the tip that [`estimate`]
//! filters out of each tracker reading.
//!
//! ```
//! use planner_core::{plan, Scenario};
//!
//! let report = plan(&Scenario::paper()).expect("the paper's scenario has a feasible path");
//! let best = report.best().expect("a feasible report names its best form");
//! assert_eq!(best.form.word().as_str(), "RL");
//! assert!(best.feasible);
//! ```
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// Small dense linear algebra on fixed arrays reads best with explicit indices.
#![allow(clippy::needless_range_loop)]
// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod chance;
pub mod check;
pub mod device;
pub mod error;
pub mod estimate;
pub mod execute;
pub(crate) mod fmath;
pub(crate) mod matmul;
pub mod model;
pub(crate) mod optim;
pub mod report;
pub(crate) mod search;
pub mod session;
pub mod steer;
pub mod wire;

pub use error::{Field, PlanError};
pub use execute::ScheduledPlan;
pub use model::form::{Form, FormSet, SegmentKind, FORM_COUNT, MAX_CONTROL_DEGREE};
pub use model::scenario::{
    Scenario, DEVICE_MAX_OBSTACLES, HOST_MAX_OBSTACLES, MAX_CURVATURE_RESERVE, MAX_OBSTACLES,
};
pub use report::{FormOutcome, Insertion, PlanReport, SegmentPlan, SolveStatus};
pub use session::{plan, plan_scheduled, PlanSession};
