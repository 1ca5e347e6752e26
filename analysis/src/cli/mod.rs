//! The analysis subcommands of `needle` (sweep, rrt, compare, approx, plot, `plan --plot`):
//! argument parsing and output, one file per command; the work itself is in the other modules of
//! `analysis`.

mod approx;
mod args;
mod compare;
pub mod output;
mod plot;
mod rrt;
mod sweep;

pub use approx::{run_approx, ApproxArgs, ApproxJson};
pub use args::{RrtArgs, ScenarioArgs, ScenarioFileArgs};
pub use compare::{run_compare, CompareArgs};
pub use plot::{
    anatomy_slices_svg, plan_scene_paths, run_plot, write_plan_plot, PlotArgs, Slicing,
};
pub use rrt::{run_rrt, RrtCmd, RrtJson};
pub use sweep::{run_sweep, SweepArgs};
