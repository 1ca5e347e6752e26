//! From plan to motion: the motor schedule a two-stage needle driver executes (insertion u1,
//! rotation u2), and the nominal model that executes it, which re-checks every schedule against
//! the scenario independently of the planner; a finished plan carries its best form's schedule
//! ([`ScheduledPlan`]), on the device as on the host.

pub mod nominal;
pub mod schedule;
pub mod scheduled;

pub use scheduled::ScheduledPlan;
