//! Analysis around the planner: weight sweeps, the RRT baseline and the comparison with it,
//! polygon obstacles turned into circles, and SVG plots of all of these.

pub mod approx;
pub mod compare;
pub mod geometry;
pub mod parallel;
pub mod rng;
pub mod rrt;
pub mod sweep;
pub mod plot;
pub mod svg;
pub mod sweep_plot;
pub mod cli;
pub mod plan_file;
