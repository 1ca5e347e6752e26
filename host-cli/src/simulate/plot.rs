//! The picture of a simulation: the plan, the obstacles and the executed paths as a thin tube
//! around it (both projections in 3-D), drawn with the scenario plot of [`crate::analysis::plot`].

use crate::analysis::plot::{colour_of, scene_svg, PlotPath, Scene};
use crate::report::path_points;
use crate::scenario::ObstacleShape;
use needle_sim::Run;
use planner_core::{FormOutcome, Scenario};

/// Most executed paths drawn (the first runs): enough for the tube, a file a viewer opens.
pub const MAX_DRAWN: usize = 300;

/// The SVG of `runs` around the plan `outcome`.
pub fn simulate_svg(
    scenario: &Scenario,
    shapes: &[ObstacleShape],
    outcome: &FormOutcome,
    runs: &[Run],
    title: &str,
) -> String {
    let drawn = runs.len().min(MAX_DRAWN);
    let collided = runs.iter().filter(|r| r.collided).count();
    let scene = Scene {
        title: title.to_string(),
        shapes,
        paths: vec![PlotPath {
            label: format!("{}: planned, L = {:.1} mm", outcome.form, outcome.length),
            form: outcome.form.to_string(),
            colour: colour_of(outcome.form),
            points: path_points(scenario, outcome),
            best: true,
        }],
        notes: vec![
            format!("red: {drawn} of {} simulated runs", runs.len()),
            format!("(open loop; {collided} entered an obstacle)"),
        ],
        tree: vec![],
        executed: runs[..drawn].iter().map(|r| r.points.clone()).collect(),
    };
    scene_svg(scenario, &scene)
}
