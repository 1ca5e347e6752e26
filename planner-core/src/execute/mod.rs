//! From plan to motion: the motor schedule a two-stage needle driver executes (insertion u1,
//! rotation u2), and the nominal model that executes it, which re-checks every schedule against
//! the scenario independently of the planner; a finished plan carries its best form's schedule
//! ([`ScheduledPlan`]), on the device as on the host.

pub mod apriori;
pub mod nominal;
mod obstacle_risk;
pub mod perturbation;
pub mod pieces;
pub mod plan_with_schedule;
pub mod risk;
mod risk_kept;
pub mod schedule;
pub mod spread;

pub use plan_with_schedule::ScheduledPlan;
