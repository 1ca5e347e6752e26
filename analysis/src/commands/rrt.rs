//! `needle rrt`, and the RRT's picture that `needle compare` shares.

use super::options::{RrtSettings, ScenarioSource};
use super::output::{title_of, write};
use crate::pieces::{path_points, Segment};
use crate::plot::{scene_svg, PlotPath, Scene};
use crate::rrt;
use anyhow::Result;
use needle_report::json::{finite, write_sorted, SegmentJson};
use planner_core::Scenario;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::io::Write;
use std::path::PathBuf;

/// What `needle rrt` is asked.
#[derive(Clone, Debug)]
pub struct RrtOptions {
    /// The scenario (the RRT plans no path forms, so it takes no forms or degree).
    pub scenario: ScenarioSource,
    /// The RRT's settings.
    pub rrt: RrtSettings,
    /// Seed of the random samples.
    pub seed: u64,
    /// Print one JSON object instead of the summary.
    pub json: bool,
    /// Draw the tree and the path (SVG).
    pub plot: Option<PathBuf>,
}

/// The RRT's path and its tree as lines to draw.
pub(super) fn rrt_scene_paths(
    scenario: &Scenario,
    o: &rrt::Outcome,
) -> (PlotPath, Vec<Vec<[f32; 3]>>) {
    let radius = scenario.needle.curvature_radius;
    let tree = o
        .tree
        .iter()
        .skip(1)
        .map(|n| {
            let parent = o.tree[n.parent].frame;
            path_points(&parent, &[n.piece], radius, 2.5)
        })
        .collect();
    let s = &o.score;
    let path = PlotPath {
        label: format!(
            "RRT: N = {}, F = {:.2}, L = {:.1} mm, target error {:.2} mm",
            s.control_degree, s.objective, s.length, s.target_error
        ),
        form: "RRT".into(),
        colour: "#d62728".into(),
        points: path_points(&o.first, &o.pieces, radius, 1.0),
        best: true,
    };
    (path, tree)
}

/// The `needle rrt --json` object: the path's score, the run's effort, its segments and points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RrtJson {
    /// L (mm).
    pub length: Option<f64>,
    /// D.
    pub risk: Option<f64>,
    /// H.
    pub penalty: Option<f64>,
    /// N: segments after merging.
    pub control_degree: usize,
    /// F.
    pub objective: Option<f64>,
    /// Smallest clearance to an obstacle surface (mm).
    pub min_clearance: Option<f64>,
    /// Distance from the path's end to the target (mm).
    pub target_error: Option<f64>,
    /// Wall-clock time of the run (µs).
    pub time_us: u64,
    /// Samples drawn.
    pub iterations: usize,
    /// Nodes grown.
    pub nodes: usize,
    /// The merged segments.
    pub segments: Vec<SegmentJson>,
    /// Points at most 1 mm apart from the entry to the end.
    pub points: Vec<[f64; 3]>,
}

impl RrtJson {
    /// The report of run `o` in `scenario`.
    pub fn new(scenario: &Scenario, o: &rrt::Outcome) -> RrtJson {
        let s = &o.score;
        let radius = scenario.needle.curvature_radius;
        RrtJson {
            length: finite(s.length),
            risk: finite(s.risk),
            penalty: finite(s.penalty),
            control_degree: s.control_degree,
            objective: finite(s.objective),
            min_clearance: finite(s.min_clearance),
            target_error: finite(s.target_error),
            time_us: o.time_us,
            iterations: o.iterations,
            nodes: o.tree.len(),
            segments: o.segments.iter().map(Segment::to_json).collect(),
            points: path_points(&o.first, &o.pieces, radius, 1.0)
                .into_iter()
                .map(|p| p.map(f64::from))
                .collect(),
        }
    }
}

impl fmt::Display for RrtJson {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_sorted(self, f)
    }
}

/// Runs `needle rrt`.
pub fn run_rrt(a: &RrtOptions) -> Result<()> {
    let (scenario, shapes) = a.scenario.load()?;
    let o = rrt::run(&scenario, &a.rrt.options(a.seed))?;
    if a.json {
        writeln!(std::io::stdout(), "{}", RrtJson::new(&scenario, &o))?;
    } else {
        let s = &o.score;
        writeln!(
            std::io::stdout(),
            "RRT (seed {}): L = {:.2} mm, D = {:.4}, N = {}, F = {:.3}, clearance {:.2} mm, \
             target error {:.3} mm (tolerance {}), {} nodes, {} samples, {:.1} ms",
            a.seed,
            s.length,
            s.risk,
            s.control_degree,
            s.objective,
            s.min_clearance,
            s.target_error,
            a.rrt.tolerance,
            o.tree.len(),
            o.iterations,
            o.time_us as f64 / 1000.0
        )?;
        for (i, g) in o.segments.iter().enumerate() {
            writeln!(
                std::io::stdout(),
                "  segment {}: {} {:.2} mm, bevel {:.1} deg",
                i + 1,
                g.kind.letter(),
                g.length,
                g.bevel_deg
            )?;
        }
    }
    if let Some(p) = &a.plot {
        let (path, tree) = rrt_scene_paths(&scenario, &o);
        let scene = Scene {
            title: format!("{}: RRT, seed {}", title_of(&a.scenario.file), a.seed),
            shapes: &shapes,
            paths: vec![path],
            notes: vec![format!("tree: {} nodes (grey)", o.tree.len())],
            tree,
            executed: vec![],
        };
        write(p, &scene_svg(&scenario, &scene))?;
    }
    Ok(())
}
