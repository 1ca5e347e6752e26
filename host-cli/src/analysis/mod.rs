//! Analysis around the planner: weight sweeps, the RRT baseline and the comparison with it, and
//! SVG plots of these and of polygon obstacles' circles (the polygons themselves are part of the
//! scenario model, [`crate::scenario`]). Simulated insertions (`needle simulate`) are not an
//! analysis of a plan but its execution: [`crate::simulate`].

pub mod cli;
pub mod compare;
pub mod parallel;
pub mod pieces;
pub mod plan_file;
pub mod plot;
pub mod rrt;
pub mod slice_maps;
pub mod slices;
pub mod svg;
pub mod sweep;
pub mod sweep_plot;
