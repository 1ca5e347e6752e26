//! The analysis subcommands of `needle` (sweep, rrt, compare, approx, plot, `plan --plot`): what
//! each is asked and what it prints, one file per command; their flags are the `needle`
//! binary's, the work itself is in the other modules of `analysis`.

mod approx;
mod compare;
mod options;
pub mod output;
mod plot;
mod rrt;
mod sweep;

pub use approx::{run_approx, ApproxJson, ApproxOptions};
pub use compare::{run_compare, CompareOptions};
pub use options::{RrtSettings, ScenarioOptions, ScenarioSource};
pub use plot::{
    anatomy_slices_svg, plan_scene_paths, run_plot, write_plan_plot, PlotOptions, Slicing,
};
pub use rrt::{run_rrt, RrtJson, RrtOptions};
pub use sweep::{run_sweep, SweepOptions};
