//! Analysis around the planner: weight sweeps, the RRT baseline and the comparison with it,
//! simulated insertions of a plan (`needle simulate`), and
//! SVG plots of these and of polygon obstacles' circles (the polygons themselves are part of the
//! scenario model, [`crate::scenario`]).

pub mod cli;
pub mod compare;
pub mod parallel;
pub mod pieces;
pub mod plan_file;
pub mod plot;
pub mod rrt;
pub mod simulate;
pub mod svg;
pub mod sweep;
pub mod sweep_plot;
