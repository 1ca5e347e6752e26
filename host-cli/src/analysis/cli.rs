//! The analysis subcommands of `needle` (sweep, rrt, compare, approx, plot, `plan --plot`): argument
//! parsing and output; the work itself is in the sibling modules.

use super::plot::{colour_of, scene_svg, PlotPath, Scene};
use super::sweep_plot::sweep_svg;
use super::{compare, parallel, rrt, sweep};
use crate::report::{path_points, PlanJson};
use crate::scenario::approx::Method;
use crate::scenario::{load_scenario_shapes, parse_form, ObstacleShape, ScenarioFile};
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use planner_core::form::FormSet;
use planner_core::{PlanReport, Scenario};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// The scenario and what to plan in it.
#[derive(clap::Args, Clone, Debug)]
pub struct ScenarioArgs {
    /// Scenario file (TOML, see examples/paper.toml).
    pub file: PathBuf,
    /// Largest control degree N to try (overrides the file).
    #[arg(long)]
    pub max_degree: Option<u8>,
    /// Comma-separated forms to try, e.g. RL,LRL (overrides the file).
    #[arg(long, value_delimiter = ',')]
    pub forms: Option<Vec<String>>,
    /// Turn every polygon obstacle into circles this way: circumscribed, segmented or bordered.
    #[arg(long, ignore_case = true)]
    pub approx: Option<Method>,
}

impl ScenarioArgs {
    /// Loads the file and applies the overrides.
    pub fn load(&self) -> Result<(Scenario, Vec<ObstacleShape>)> {
        let (mut scenario, shapes) = load_scenario_shapes(&self.file, self.approx)?;
        if let Some(n) = self.max_degree {
            scenario.options.max_control_degree = n;
        }
        if let Some(words) = &self.forms {
            let mut set = FormSet::default();
            for w in words {
                set.insert(parse_form(w)?);
            }
            scenario.options.forms = set;
            if self.max_degree.is_none() {
                scenario.options.max_control_degree = planner_core::MAX_CONTROL_DEGREE as u8;
            }
        }
        scenario.validate().context("invalid planning options")?;
        Ok((scenario, shapes))
    }
}

/// A progress bar on a terminal, nothing otherwise.
fn progress(len: usize, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
}

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

fn title_of(file: &Path) -> String {
    file.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// `needle sweep`
#[derive(clap::Args, Clone, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Weight to vary: length, risk, penalty or control.
    #[arg(long, ignore_case = true)]
    pub weight: sweep::Weight,
    /// First value.
    #[arg(long)]
    pub from: f64,
    /// Last value.
    #[arg(long)]
    pub to: f64,
    /// Number of values, both ends included.
    #[arg(long, default_value_t = 10)]
    pub steps: usize,
    /// Space the values evenly in log10.
    #[arg(long)]
    pub log: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Also write the table as CSV.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Also draw F and L against the weight (SVG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Threads (default: every core).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Runs `needle sweep`.
pub fn run_sweep(a: &SweepArgs) -> Result<()> {
    let (scenario, _) = a.scenario.load()?;
    let range = sweep::Range {
        from: a.from,
        to: a.to,
        steps: a.steps,
        log: a.log,
    };
    let bar = progress(range.values()?.len(), &format!("sweep {}", a.weight));
    let threads = a.threads.unwrap_or_else(parallel::default_threads).max(1);
    let points = sweep::run(&scenario, a.weight, &range, threads, || bar.inc(1))?;
    bar.finish_and_clear();
    if a.json {
        println!("{}", sweep::to_json(a.weight, &points));
    } else {
        print!("{}", sweep::to_table(a.weight, &points));
    }
    if let Some(p) = &a.csv {
        write(p, &sweep::to_csv(a.weight, &points))?;
    }
    if let Some(p) = &a.plot {
        let title = format!(
            "{}: sweep of weight {} ({} values)",
            title_of(&a.scenario.file),
            a.weight,
            points.len()
        );
        write(p, &sweep_svg(a.weight, &points, a.log, &title))?;
    }
    Ok(())
}

/// RRT settings shared by `rrt` and `compare`.
#[derive(clap::Args, Clone, Debug)]
pub struct RrtArgs {
    /// Edge length (mm).
    #[arg(long, default_value_t = 10.0)]
    pub step: f32,
    /// Stop once the tip is this close to the target (mm).
    #[arg(long, default_value_t = 1.0)]
    pub tolerance: f32,
    /// Most samples before giving up.
    #[arg(long, default_value_t = 20_000)]
    pub iterations: usize,
    /// Share of samples aimed at the target.
    #[arg(long, default_value_t = 0.2)]
    pub goal_bias: f64,
}

impl RrtArgs {
    fn options(&self, seed: u64) -> rrt::Options {
        rrt::Options {
            step: self.step,
            tolerance: self.tolerance,
            seed,
            iterations: self.iterations,
            goal_bias: self.goal_bias,
            ..rrt::Options::default()
        }
    }
}

/// `needle rrt`
#[derive(clap::Args, Clone, Debug)]
pub struct RrtCmd {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub rrt: RrtArgs,
    /// Seed of the random samples.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Draw the tree and the path (SVG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

fn rrt_json(scenario: &Scenario, o: &rrt::Outcome) -> serde_json::Value {
    let s = &o.score;
    serde_json::json!({
        "length": s.length,
        "risk": s.risk,
        "penalty": s.penalty,
        "control_degree": s.control_degree,
        "objective": s.objective,
        "min_clearance": s.min_clearance,
        "target_error": s.target_error,
        "time_us": o.time_us,
        "iterations": o.iterations,
        "nodes": o.tree.len(),
        "segments": o.segments.iter().map(|g| serde_json::json!({
            "kind": g.kind.letter().to_string(), "length": g.length, "bevel_deg": g.bevel_deg,
        })).collect::<Vec<_>>(),
        "points": rrt::path_points(&o.first, &o.pieces, scenario.needle.curvature_radius, 1.0),
    })
}

fn rrt_scene_paths(scenario: &Scenario, o: &rrt::Outcome) -> (PlotPath, Vec<Vec<[f32; 3]>>) {
    let radius = scenario.needle.curvature_radius;
    let tree = o
        .tree
        .iter()
        .skip(1)
        .map(|n| {
            let parent = o.tree[n.parent].frame;
            rrt::path_points(&parent, &[n.piece], radius, 2.5)
        })
        .collect();
    let s = &o.score;
    let path = PlotPath {
        label: format!(
            "RRT: N = {}, F = {:.2}, L = {:.1} mm, {:.2} mm off",
            s.control_degree, s.objective, s.length, s.target_error
        ),
        form: "RRT".into(),
        colour: "#d62728".into(),
        points: rrt::path_points(&o.first, &o.pieces, radius, 1.0),
        best: true,
    };
    (path, tree)
}

/// Runs `needle rrt`.
pub fn run_rrt(a: &RrtCmd) -> Result<()> {
    let (scenario, shapes) = a.scenario.load()?;
    let o = rrt::run(&scenario, &a.rrt.options(a.seed))?;
    if a.json {
        println!("{}", rrt_json(&scenario, &o));
    } else {
        let s = &o.score;
        println!(
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
        );
        for (i, g) in o.segments.iter().enumerate() {
            println!(
                "  segment {}: {} {:.2} mm, bevel {:.1} deg",
                i + 1,
                g.kind.letter(),
                g.length,
                g.bevel_deg
            );
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
        };
        write(p, &scene_svg(&scenario, &scene))?;
    }
    Ok(())
}

/// `needle compare`
#[derive(clap::Args, Clone, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub rrt: RrtArgs,
    /// Number of RRT runs (seeds first, first + 1, ...).
    #[arg(long, default_value_t = 11)]
    pub runs: usize,
    /// First RRT seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Threads for the RRT runs (default: every core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Draw the optimiser's best path and the median RRT run's path (SVG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// Runs `needle compare`.
pub fn run_compare(a: &CompareArgs) -> Result<()> {
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
        println!("{}", compare::to_json(&c));
    } else {
        print!("{}", compare::to_table(&c));
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
            title: format!("{}: optimiser vs RRT", title_of(&a.scenario.file)),
            shapes: &shapes,
            paths,
            notes: vec![],
            tree,
        };
        write(p, &scene_svg(&scenario, &scene))?;
    }
    Ok(())
}

/// `needle approx`
#[derive(clap::Args, Clone, Debug)]
pub struct ApproxArgs {
    /// Scenario file with polygon obstacles.
    pub file: PathBuf,
    /// circumscribed, segmented or bordered (default: each obstacle's own `approx`).
    #[arg(long, ignore_case = true)]
    pub method: Option<Method>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Draw the polygons and their circles (SVG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// Runs `needle approx`.
pub fn run_approx(a: &ApproxArgs) -> Result<()> {
    let file = ScenarioFile::load(&a.file)?;
    let shapes = file
        .obstacle_shapes(a.method)
        .with_context(|| format!("in scenario {}", a.file.display()))?;
    let mut out = Vec::new();
    let mut text = String::new();
    for s in &shapes {
        let Some((poly, ap)) = &s.polygon else {
            text.push_str(&format!("obstacles[{}]: circle, kept as is\n", s.index));
            continue;
        };
        text.push_str(&format!(
            "obstacles[{}]: polygon of {} vertices, area {:.1} mm², {}: {} circle(s), covering {:.1} mm², \
             adding {:.1} mm² ({:.0} %)\n",
            s.index,
            poly.vertices().len(),
            ap.polygon_area,
            ap.method,
            ap.circles.len(),
            ap.covered_area,
            ap.added_area(),
            100.0 * ap.added_area() / ap.polygon_area
        ));
        for c in &s.circles {
            text.push_str(&format!(
                "  center = [{:.3}, {:.3}, {:.3}], radius = {:.3}\n",
                c.center[0], c.center[1], c.center[2], c.radius
            ));
        }
        out.push(serde_json::json!({
            "index": s.index,
            "method": ap.method.name(),
            "polygon_area": ap.polygon_area,
            "covered_area": ap.covered_area,
            "added_area": ap.added_area(),
            "circles": s.circles.iter().map(|c| serde_json::json!({"center": c.center, "radius": c.radius})).collect::<Vec<_>>(),
        }));
    }
    if a.json {
        println!("{}", serde_json::json!({ "obstacles": out }));
    } else {
        print!("{text}");
    }
    if let Some(p) = &a.plot {
        let scenario = file.to_scenario_with(&shapes)?;
        let method = a
            .method
            .map_or("per-obstacle".to_string(), |m| m.to_string());
        let scene = Scene {
            title: format!("{}: obstacles as circles ({method})", title_of(&a.file)),
            shapes: &shapes,
            notes: vec!["dark: polygon; dashed: its circles".into()],
            ..Scene::default()
        };
        write(p, &scene_svg(&scenario, &scene))?;
    }
    Ok(())
}

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

/// Draws every form's path of `report` to `out` (`needle plan --plot`).
pub fn write_plan_plot(
    file: &Path,
    approx: Option<Method>,
    scenario: &Scenario,
    report: &PlanReport,
    out: &Path,
) -> Result<()> {
    let shapes = ScenarioFile::load(file)?
        .obstacle_shapes(approx)
        .unwrap_or_default();
    let (paths, notes) = plan_scene_paths(scenario, report);
    let scene = Scene {
        title: format!("{}: optimal path of each form", title_of(file)),
        shapes: &shapes,
        paths,
        notes,
        tree: vec![],
    };
    write(out, &scene_svg(scenario, &scene))
}

/// `needle plot`
#[derive(clap::Args, Clone, Debug)]
pub struct PlotArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// A `needle plan --json` output to draw instead of planning again.
    #[arg(long)]
    pub plan: Option<PathBuf>,
    /// Output SVG file.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

/// Runs `needle plot`.
pub fn run_plot(a: &PlotArgs) -> Result<()> {
    let (scenario, shapes) = a.scenario.load()?;
    let (paths, notes) = match &a.plan {
        None => {
            let report = planner_core::plan(&scenario).context("planning failed")?;
            plan_scene_paths(&scenario, &report)
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
            super::plan_file::scene_paths(&scenario, &plan)
                .with_context(|| format!("in plan {}", p.display()))?
        }
    };
    let scene = Scene {
        title: format!("{}: optimal path of each form", title_of(&a.scenario.file)),
        shapes: &shapes,
        paths,
        notes,
        tree: vec![],
    };
    write(&a.output, &scene_svg(&scenario, &scene))
}
