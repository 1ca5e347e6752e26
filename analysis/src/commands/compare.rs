//! `needle compare`.

use super::options::{RrtSettings, ScenarioOptions};
use super::output::{progress, title_of, write};
use super::rrt::rrt_scene_paths;
use crate::plot::{scene_svg, PlotPath, Scene};
use crate::{compare, parallel, rrt};
use anyhow::{bail, Result};
use needle_report::path_points;
use std::io::Write;
use std::path::PathBuf;

/// What `needle compare` is asked.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    /// The scenario and what to plan in it.
    pub scenario: ScenarioOptions,
    /// The RRT's settings.
    pub rrt: RrtSettings,
    /// Number of RRT runs (seeds first, first + 1, ...), at least 1.
    pub runs: usize,
    /// First RRT seed.
    pub seed: u64,
    /// Threads for the RRT runs (`None`: every core).
    pub threads: Option<usize>,
    /// Print one JSON object instead of the table.
    pub json: bool,
    /// Draw the optimiser's best path and the median RRT run's path (SVG).
    pub plot: Option<PathBuf>,
}

/// Runs `needle compare`.
pub fn run_compare(a: &CompareOptions) -> Result<()> {
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let (scenario, shapes) = a.scenario.load()?;
    let seeds: Vec<u64> = (0..a.runs as u64).map(|k| a.seed.wrapping_add(k)).collect();
    let bar = progress(seeds.len() + 1, "compare");
    let threads = a.threads.unwrap_or_else(parallel::default_threads).max(1);
    let c = compare::run(&scenario, &a.rrt.options(a.seed), &seeds, threads, || {
        bar.inc(1)
    });
    bar.finish_and_clear();
    if a.json {
        writeln!(std::io::stdout(), "{}", compare::to_json(&c))?;
    } else {
        write!(std::io::stdout(), "{}", compare::to_table(&c))?;
    }
    if let Some(p) = &a.plot {
        let mut paths = Vec::new();
        if let Ok((report, _)) = &c.optimizer {
            if let Some(b) = report.best() {
                paths.push(PlotPath {
                    label: format!(
                        "optimiser {}: F = {:.2}, L = {:.1} mm",
                        b.form, b.objective, b.length
                    ),
                    form: b.form.to_string(),
                    colour: "#1f77b4".into(),
                    points: path_points(&scenario, b),
                    best: true,
                });
            }
        }
        // The run whose F is the median (the lower middle for an even count).
        let mut found: Vec<&rrt::Outcome> =
            c.runs.iter().filter_map(|(_, r)| r.as_ref().ok()).collect();
        found.sort_by(|x, y| x.score.objective.total_cmp(&y.score.objective));
        let mut tree = Vec::new();
        if let Some(o) = found.get(found.len().saturating_sub(1) / 2) {
            let (mut path, t) = rrt_scene_paths(&scenario, o);
            path.best = false;
            path.label = format!("median {}", path.label);
            paths.push(path);
            tree = t;
        }
        let scene = Scene {
            title: format!("{}: optimiser vs RRT", title_of(&a.scenario.source.file)),
            shapes: &shapes,
            paths,
            notes: vec![],
            tree,
            executed: vec![],
        };
        write(p, &scene_svg(&scenario, &scene))?;
    }
    Ok(())
}
