//! The analysis subcommands of `needle` (sweep, rrt, compare, approx, plot, simulate, `plan --plot`): argument
//! parsing and output, one file per command; the work itself is in the other modules of
//! `analysis`.

mod approx;
mod args;
mod compare;
mod output;
mod plot;
mod rrt;
mod simulate;
mod sweep;

pub use approx::{run_approx, ApproxArgs, ApproxJson};
pub use args::{RrtArgs, ScenarioArgs, ScenarioFileArgs};
pub use compare::{run_compare, CompareArgs};
pub use plot::{plan_scene_paths, run_plot, write_plan_plot, PlotArgs};
pub use rrt::{run_rrt, RrtCmd, RrtJson};
pub use simulate::{run_simulate, SimulateArgs};
pub use sweep::{run_sweep, SweepArgs};
