//! From plan to motion: the motor schedule a two-stage needle driver executes (insertion u1,
//! rotation u2), and the nominal model that executes it, which re-checks every schedule against
//! the scenario independently of the planner.

pub mod nominal;
pub mod schedule;
