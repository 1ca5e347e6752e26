//! Path planner for bevel-tip steerable needles: `no_std`, no heap, bounded work.
//!
//! Data flows scenario → forms → solve → check → plan:
//! [`scenario::Scenario`] is validated, each [`form::Form`] is optimised by [`solve`] (seeds, then
//! a feasible-path SQP over the insertion posture and the segment parameters), every candidate is
//! re-checked by [`verify`] independently of the optimiser, and [`planner`] keeps the best form.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// Small dense linear algebra on fixed arrays reads best with explicit indices.
#![allow(clippy::needless_range_loop)]
// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod clearance;
pub mod error;
pub mod escape;
pub mod fmath;
pub mod form;
pub mod kinematics;
pub mod plan;
pub mod planar;
pub mod planner;
pub mod problem;
pub mod qp;
pub mod scenario;
pub mod seeds;
pub mod service;
pub mod solve;
pub mod sqp;
pub mod verify;
pub mod wire;

pub use error::{Field, PlanError};
pub use form::{Form, FormSet, SegmentKind, FORM_COUNT, MAX_CONTROL_DEGREE};
pub use plan::{FormOutcome, Insertion, PlanReport, SegmentPlan, SolveStatus};
pub use planner::{plan, PlanSession};
pub use scenario::{Scenario, MAX_OBSTACLES};
