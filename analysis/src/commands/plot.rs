//! `needle plot` and `needle plan --plot`.

use super::options::ScenarioOptions;
use super::output::{title_of, write};
use crate::plan_file;
use crate::plot::{colour_of, scene_svg, PlotPath, Scene, Strands};
use crate::slice_maps::{slice_maps, slice_point, SliceAt};
use crate::slices::{slices_svg, SliceScene};
use anyhow::{bail, Context, Result};
use needle_report::{path_points, PlanJson};
use needle_scenario::approx::Method;
use needle_scenario::ScenarioFile;
use planner_core::{PlanReport, Scenario};
use std::path::{Path, PathBuf};

/// Paths and legend notes for every form of a plan.
pub fn plan_scene_paths(scenario: &Scenario, report: &PlanReport) -> (Vec<PlotPath>, Vec<String>) {
    let mut paths = Vec::new();
    let mut notes = Vec::new();
    let best = report.best().map(|b| b.form);
    for o in &report.forms {
        if o.feasible {
            let is_best = Some(o.form) == best;
            paths.push(PlotPath {
                label: format!(
                    "{}{}: F = {:.2}, L = {:.1} mm",
                    o.form,
                    if is_best { " (best)" } else { "" },
                    o.objective,
                    o.length
                ),
                form: o.form.to_string(),
                colour: colour_of(o.form),
                points: path_points(scenario, o),
                best: is_best,
            });
        } else {
            notes.push(format!("{}: no feasible path", o.form));
        }
    }
    (paths, notes)
}

/// Draws every form's path of `report` to `out` (`needle plan --plot`): the two projections, or
/// with `[[anatomy]]` the slices of its label maps through the best path's point nearest an
/// obstacle.
pub fn write_plan_plot(
    file: &Path,
    approx: Option<Method>,
    scenario: &Scenario,
    report: &PlanReport,
    out: &Path,
) -> Result<()> {
    let loaded = ScenarioFile::load(file)?;
    let (paths, notes) = plan_scene_paths(scenario, report);
    if !loaded.anatomy.is_empty() {
        let title = format!(
            "{}: label map slices and the optimal path of each form",
            title_of(file)
        );
        let scene = Slicing {
            file: &loaded,
            paths: &paths,
            notes: &notes,
            executed: &[],
            at: &SliceAt::Closest,
        };
        return write(out, &anatomy_slices_svg(scenario, &scene, &title)?);
    }
    let shapes = loaded.obstacle_shapes(approx).unwrap_or_default();
    let scene = Scene {
        title: format!("{}: optimal path of each form", title_of(file)),
        shapes: &shapes,
        paths,
        notes,
        tree: vec![],
        executed: vec![],
    };
    write(out, &scene_svg(scenario, &scene))
}

/// What to slice and draw for a scenario with `[[anatomy]]`.
pub struct Slicing<'a> {
    /// The scenario file (its `[[anatomy]]` maps are read again).
    pub file: &'a ScenarioFile,
    /// Planned paths.
    pub paths: &'a [PlotPath],
    /// Extra legend lines.
    pub notes: &'a [String],
    /// Simulated paths.
    pub executed: &'a [Strands],
    /// Where the planes cross.
    pub at: &'a SliceAt,
}

/// The slices of the scenario's label maps with its paths, as SVG.
pub fn anatomy_slices_svg(scenario: &Scenario, s: &Slicing<'_>, title: &str) -> Result<String> {
    let maps = slice_maps(s.file)?;
    let point = slice_point(s.at, &maps, scenario, s.paths.iter().find(|p| p.best))?;
    let scene = SliceScene {
        title: title.to_string(),
        maps: &maps,
        paths: s.paths,
        notes: s.notes,
        executed: s.executed,
        at: point,
    };
    Ok(slices_svg(scenario, &scene))
}

/// What `needle plot` is asked.
#[derive(Clone, Debug)]
pub struct PlotOptions {
    /// The scenario and what to plan in it.
    pub scenario: ScenarioOptions,
    /// A `needle plan --json` output to draw instead of planning again.
    pub plan: Option<PathBuf>,
    /// Output SVG file.
    pub output: PathBuf,
    /// With `[[anatomy]]`: where the axial, coronal and sagittal slices of the label maps cross
    /// (`None`: the best path's point nearest an obstacle); it must lie inside a label map.
    pub slice_at: Option<SliceAt>,
    /// With `[[anatomy]]`: draw the two projections of a scenario without anatomy instead of
    /// the slices.
    pub projections: bool,
}

/// Runs `needle plot`.
pub fn run_plot(a: &PlotOptions) -> Result<()> {
    let (mut scenario, shapes) = a.scenario.load()?;
    let (paths, notes) = match &a.plan {
        None => {
            // Planned as `needle plan` plans it (its execution, the bound's rounds, the
            // curvature reserve kept), so the plot draws the plan the command prints.
            let execution = needle_scenario::load_execution(&a.scenario.source.file)?;
            let made = needle_report::local::plan_locally(&scenario, &execution)
                .context("planning failed")?;
            scenario = made.scenario.clone();
            plan_scene_paths(&scenario, made.report())
        }
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read plan {}", p.display()))?;
            let plan: PlanJson = serde_json::from_str(&text).with_context(|| {
                format!(
                    "{} is not a plan (expected `needle plan --json` output)",
                    p.display()
                )
            })?;
            plan_file::scene_paths(&scenario, &plan)
                .with_context(|| format!("in plan {}", p.display()))?
        }
    };
    let file = ScenarioFile::load(&a.scenario.source.file)?;
    if !file.anatomy.is_empty() && !a.projections {
        let at = a.slice_at.clone().unwrap_or(SliceAt::Closest);
        let scene = Slicing {
            file: &file,
            paths: &paths,
            notes: &notes,
            executed: &[],
            at: &at,
        };
        let title = format!(
            "{}: label map slices and the optimal path of each form",
            title_of(&a.scenario.source.file)
        );
        return write(&a.output, &anatomy_slices_svg(&scenario, &scene, &title)?);
    }
    if a.slice_at.is_some() {
        bail!(
            "--slice-at: {} has no [[anatomy]] to slice",
            a.scenario.source.file.display()
        );
    }
    let scene = Scene {
        title: format!(
            "{}: optimal path of each form",
            title_of(&a.scenario.source.file)
        ),
        shapes: &shapes,
        paths,
        notes,
        tree: vec![],
        executed: vec![],
    };
    write(&a.output, &scene_svg(&scenario, &scene))
}
