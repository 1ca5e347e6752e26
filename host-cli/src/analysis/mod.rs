//! Analysis around the planner: weight sweeps, the RRT baseline and the comparison with it,
//! polygon obstacles turned into circles, and SVG plots of all of these.

pub mod approx;
pub mod cli;
pub mod compare;
pub mod geometry;
pub mod parallel;
pub mod plan_file;
pub mod plot;
pub mod rng;
pub mod rrt;
pub mod svg;
pub mod sweep;
pub mod sweep_plot;
