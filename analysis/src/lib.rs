//! Analysis around the planner: weight sweeps, the RRT baseline and the comparison with it, and
//! SVG plots of these and of polygon obstacles' circles (the polygons themselves are part of the
//! scenario model, [`needle_scenario`]). Simulated insertions (`needle simulate`) are not an
//! analysis of a plan but its execution: the `needle-simulate` crate. [`bench`] times planning
//! (`needle bench`) and [`scale`] draws its hundreds of spheres; [`commands`] is what the
//! analysis commands are asked and print (their flags are the `needle` binary's).
//!
//! A weight sweep, the analysis most callers start from:
//!
//! ```
//! use needle_analysis::sweep::{run, Range, Weight};
//! use planner_core::Scenario;
//!
//! let range = Range { from: 0.5, to: 2.0, steps: 3, log: false };
//! let points = run(&Scenario::paper(), Weight::Risk, &range, 2, || {})?;
//! let values: Vec<f64> = points.iter().map(|p| p.value).collect();
//! assert_eq!(values, [0.5, 1.25, 2.0]);
//! assert!(points.iter().all(|p| p.best().is_some_and(|b| b.feasible)));
//! # Ok::<(), anyhow::Error>(())
//! ```

pub mod bench;
pub mod commands;
pub mod compare;
pub mod parallel;
pub mod pieces;
pub mod plan_file;
pub mod plot;
pub mod rrt;
pub mod scale;
pub mod slice_maps;
pub mod slices;
pub mod svg;
pub mod sweep;
pub mod sweep_plot;
