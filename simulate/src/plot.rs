//! The picture of a simulation: the plan, the obstacles and the executed paths as thin tubes
//! around it (both projections in 3-D), drawn with the scenario plot of [`needle_analysis::plot`]:
//! open-loop runs in red, or, closed loop, the runs not stopped in red, those stopped
//! before it dashed in orange and the same worlds open loop (`--compare-open-loop`) in blue, each
//! with its legend entry. With `[[anatomy]]`, the same over slices of the label maps.

use needle_analysis::commands::{anatomy_slices_svg, Slicing};
use needle_analysis::plot::{colour_of, scene_svg, PlotPath, Scene, Strands};
use needle_analysis::slice_maps::SliceAt;
use needle_report::path_points;
use needle_scenario::{ObstacleShape, ScenarioFile};
use needle_sim::{ClosedRun, Run};
use planner_core::{FormOutcome, Scenario};

/// Most executed paths drawn of each kind (the first runs): enough for a tube, a file a viewer
/// opens. The simulation keeps no more than these of `--runs` (without `--detail`).
pub const MAX_DRAWN: usize = 300;

/// The runs to draw: open loop, closed loop, or both.
pub struct Executed<'a> {
    /// Open-loop runs.
    pub open: Option<&'a [Run]>,
    /// Closed-loop runs.
    pub closed: Option<&'a [ClosedRun]>,
}

const RED: &str = "#d62728";
const ORANGE: &str = "#ff7f0e";
const BLUE: &str = "#1f77b4";

/// "(k entered an obstacle)" over `runs`.
fn collided<'a>(runs: impl Iterator<Item = &'a Run>) -> String {
    let k = runs.filter(|r| r.collided).count();
    format!("({k} entered an obstacle)")
}

/// The open-loop runs' strands, the first [`MAX_DRAWN`].
fn open_strands(runs: &[Run], label: &str, class: &str, colour: &str) -> Strands {
    let drawn = runs.len().min(MAX_DRAWN);
    Strands {
        label: format!(
            "{label}: {drawn} of {} runs {}",
            runs.len(),
            collided(runs.iter())
        ),
        class: class.to_string(),
        colour: colour.to_string(),
        dashed: false,
        lines: runs[..drawn].iter().map(|r| r.points.clone()).collect(),
    }
}

/// The closed-loop runs' strands: those the controller did not stop among the first
/// [`MAX_DRAWN`] (each reached, missed or collided: the legend counts the collisions), and the
/// first [`MAX_DRAWN`] stopped before the target.
fn closed_strands(runs: &[ClosedRun]) -> [Strands; 2] {
    let reached: Vec<&Run> = runs
        .iter()
        .filter(|c| c.stop_reason.is_none())
        .map(|c| &c.run)
        .collect();
    let stopped: Vec<&Run> = runs
        .iter()
        .filter(|c| c.stop_reason.is_some())
        .map(|c| &c.run)
        .collect();
    let reached_drawn: Vec<Vec<[f32; 3]>> = runs
        .iter()
        .take(MAX_DRAWN)
        .filter(|c| c.stop_reason.is_none())
        .map(|c| c.run.points.clone())
        .collect();
    let stopped_drawn = stopped.len().min(MAX_DRAWN);
    [
        Strands {
            label: format!(
                "closed loop, not stopped (reached, missed or collided): {} of {} runs {}",
                reached_drawn.len(),
                reached.len(),
                collided(reached.iter().copied())
            ),
            class: "executed".into(),
            colour: RED.into(),
            dashed: false,
            lines: reached_drawn,
        },
        Strands {
            label: format!(
                "closed loop, stopped before the target: {stopped_drawn} of {} runs",
                stopped.len()
            ),
            class: "executed stopped".into(),
            colour: ORANGE.into(),
            dashed: true,
            lines: stopped[..stopped_drawn]
                .iter()
                .map(|r| r.points.clone())
                .collect(),
        },
    ]
}

/// The strands of `executed`, drawn in this order: the open loop under the closed loop,
/// stopped runs on top.
fn all_strands(executed: &Executed<'_>) -> Vec<Strands> {
    let mut strands = Vec::new();
    match (executed.open, executed.closed) {
        (Some(open), None) => strands.push(open_strands(open, "open loop", "executed", RED)),
        (open, Some(closed)) => {
            if let Some(open) = open {
                let label = "open loop, same worlds";
                strands.push(open_strands(open, label, "executed open-loop", BLUE));
            }
            strands.extend(closed_strands(closed));
        }
        (None, None) => {}
    }
    strands
}

/// The planned path of `outcome`, drawn as the best.
fn planned(scenario: &Scenario, outcome: &FormOutcome) -> PlotPath {
    PlotPath {
        label: format!("{}: planned, L = {:.1} mm", outcome.form, outcome.length),
        form: outcome.form.to_string(),
        colour: colour_of(outcome.form),
        points: path_points(scenario, outcome),
        best: true,
    }
}

/// The legend's note on how many paths are drawn.
fn drawn_note() -> String {
    format!("at most {MAX_DRAWN} paths of each kind are drawn")
}

/// The SVG of the executed runs around the plan `outcome`.
pub fn simulate_svg(
    scenario: &Scenario,
    shapes: &[ObstacleShape],
    outcome: &FormOutcome,
    executed: &Executed<'_>,
    title: &str,
) -> String {
    let scene = Scene {
        title: title.to_string(),
        shapes,
        paths: vec![planned(scenario, outcome)],
        notes: vec![drawn_note()],
        tree: vec![],
        executed: all_strands(executed),
    };
    scene_svg(scenario, &scene)
}

/// The same with `[[anatomy]]`: slices of the label maps through the planned path's point
/// nearest an obstacle, the runs projected onto each.
pub fn simulate_slices_svg(
    scenario: &Scenario,
    file: &ScenarioFile,
    outcome: &FormOutcome,
    executed: &Executed<'_>,
    title: &str,
) -> anyhow::Result<String> {
    let paths = [planned(scenario, outcome)];
    let strands = all_strands(executed);
    let notes = [drawn_note()];
    let scene = Slicing {
        file,
        paths: &paths,
        notes: &notes,
        executed: &strands,
        at: &SliceAt::Closest,
    };
    anatomy_slices_svg(scenario, &scene, title)
}
