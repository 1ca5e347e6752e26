//! The problem as stated: the scenario, the path forms, the needle's kinematics and the exact
//! clearance between a path and an obstacle (and, for the seeds, the same geometry in a plane).

pub mod clearance;
pub mod form;
pub mod kinematics;
pub(crate) mod planar;
pub mod scenario;
