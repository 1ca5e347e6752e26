//! The problem as stated: the scenario, the path forms, the needle's kinematics and the exact
//! clearance between a path and an obstacle (the same geometry in a plane, which only the seeds
//! use, is `search::in_plane_geometry`).

pub mod broad;
#[cfg(test)]
mod broad_exact;
pub mod clearance;
pub mod form;
pub mod kinematics;
pub mod scenario;
