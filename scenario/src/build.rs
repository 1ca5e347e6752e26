//! From a scenario file to the core's [`Scenario`], checking what the core checks so that
//! errors name the file's keys.

use super::approx::Method;
use super::execution::CLOSED_LOOP_CURVATURE_RESERVE;
use super::file::ScenarioFile;
use super::shapes::ObstacleShape;
use anyhow::{bail, Context, Result};
use planner_core::model::form::{Form, FormSet};
use planner_core::model::scenario::{
    Driver, Entry, Needle, Obstacle, PlannerOptions, RiskMeasure, Target, Weights, Workspace,
    DEFAULT_NEEDLE_LENGTH_MM,
};
use planner_core::{PlanError, Scenario, MAX_OBSTACLES};
use std::path::Path;

/// `needle.max_arc_deg` when the file has none: at most a half turn per arc.
pub const DEFAULT_MAX_ARC_DEG: f32 = 180.0;
/// `entry.max_tilt_deg` when the file has none.
pub const DEFAULT_MAX_TILT_DEG: f32 = 60.0;
/// `target.tolerance` when the file has none (mm).
pub const DEFAULT_TOLERANCE: f32 = 0.1;

impl ScenarioFile {
    /// `planner.curvature_reserve` where the file says nothing of it: the closed loop's
    /// ([`CLOSED_LOOP_CURVATURE_RESERVE`]) unless `execution.mode` is `"open_loop"` (the
    /// closed loop is the default mode), else none.
    fn default_curvature_reserve(&self) -> f32 {
        if self.planned_open_loop() {
            0.0
        } else {
            CLOSED_LOOP_CURVATURE_RESERVE
        }
    }

    /// Builds the core scenario, checking what the core checks (so errors name the file's keys).
    pub fn to_scenario(&self) -> Result<Scenario> {
        self.to_scenario_with(&self.obstacle_shapes(None)?)
    }

    /// Builds the core scenario with the obstacles' circles from [`Self::obstacle_shapes`].
    pub fn to_scenario_with(&self, shapes: &[ObstacleShape]) -> Result<Scenario> {
        let mut obstacles = heapless::Vec::<Obstacle, MAX_OBSTACLES>::new();
        let count: usize = shapes.iter().map(|s| s.circles.len()).sum();
        if count > MAX_OBSTACLES {
            let polygons = shapes.iter().filter(|s| s.polygon.is_some()).count();
            let err = PlanError::TooManyObstacles {
                given: count.min(u16::MAX as usize) as u16,
                capacity: MAX_OBSTACLES as u16,
            };
            if polygons > 0 {
                bail!("{err}; {polygons} polygon obstacle(s) became circles: a coarser approximation (circumscribed or segmented) needs fewer");
            }
            bail!(err);
        }
        for c in shapes.iter().flat_map(|s| &s.circles) {
            // Cannot fail: the count was checked above.
            let _ = obstacles.push(*c);
        }
        let p = self.planner.clone().unwrap_or_default();
        let workspace = match p.plane.as_deref() {
            None => Workspace::Space,
            Some(s) if s.eq_ignore_ascii_case("yz") => Workspace::PlaneYz,
            Some(other) => bail!(
                "planner.plane = {other:?}: only \"yz\" is supported (or leave it out for 3-D)"
            ),
        };
        let risk = match p.risk.as_deref() {
            None | Some("mean") => RiskMeasure::Mean,
            Some("sum") => RiskMeasure::Sum,
            Some(other) => bail!("planner.risk = {other:?}: use \"mean\" or \"sum\""),
        };
        if p.forms.as_ref().is_some_and(|f| f.is_empty()) {
            bail!(
                "planner.forms is empty: list forms such as [\"RL\"], or leave the key out to \
                 try every form up to planner.max_control_degree"
            );
        }
        let mut forms = FormSet::default();
        for word in p.forms.iter().flatten() {
            let f = parse_form(word)?;
            forms.insert(f);
        }
        let defaults = Weights::default();
        let w = self.weights.clone();
        let weights = Weights {
            length: w.as_ref().and_then(|w| w.length).unwrap_or(defaults.length),
            risk: w.as_ref().and_then(|w| w.risk).unwrap_or(defaults.risk),
            penalty: w
                .as_ref()
                .and_then(|w| w.penalty)
                .unwrap_or(defaults.penalty),
            control: w
                .as_ref()
                .and_then(|w| w.control)
                .unwrap_or(defaults.control),
        };
        let scenario = Scenario {
            needle: Needle {
                curvature_radius: self.needle.curvature_radius,
                max_arc_deg: self.needle.max_arc_deg.unwrap_or(DEFAULT_MAX_ARC_DEG),
                max_line_length: self.needle.max_line_length.unwrap_or(0.0),
                length: self.needle.length.unwrap_or(DEFAULT_NEEDLE_LENGTH_MM),
            },
            entry: Entry {
                position: self.entry_position()?,
                direction: self.entry.direction,
                max_tilt_deg: self.entry.max_tilt_deg.unwrap_or(DEFAULT_MAX_TILT_DEG),
            },
            target: Target {
                position: self.target_position()?,
                tolerance: self.target.tolerance.unwrap_or(DEFAULT_TOLERANCE),
            },
            obstacles,
            weights,
            options: PlannerOptions {
                max_control_degree: p.max_control_degree.unwrap_or(3),
                forms,
                workspace,
                risk,
                min_clearance: p.min_clearance.unwrap_or(0.0),
                curvature_reserve: p
                    .curvature_reserve
                    .unwrap_or_else(|| self.default_curvature_reserve()),
                risk_within_mm: p.risk_within_mm,
            },
            driver: {
                let d = self.driver.clone().unwrap_or_default();
                let default = Driver::DEFAULT;
                Driver {
                    insert_speed: d.insert_speed.unwrap_or(default.insert_speed),
                    rotate_speed: d.rotate_speed.unwrap_or(default.rotate_speed),
                    spin_rate: d.spin_rate.unwrap_or(default.spin_rate),
                    max_twist_deg: d.max_twist_deg.unwrap_or(default.max_twist_deg),
                }
            },
        };
        scenario.validate()?;
        Ok(scenario)
    }
}

/// Parses one form word, with a clear message.
pub fn parse_form(word: &str) -> Result<Form> {
    match Form::parse(word) {
        Some(f) => Ok(f),
        None => bail!(
            "{word:?} is not a path form: use R and L, no LL, at most {} letters",
            planner_core::MAX_CONTROL_DEGREE
        ),
    }
}

/// Applies the command line's `--max-degree` and `--forms` over the file's choice, then checks
/// the options. Forms given without a degree may use the largest degree the core plans.
pub fn restrict(
    scenario: &mut Scenario,
    max_degree: Option<u8>,
    forms: Option<&[String]>,
) -> Result<()> {
    if let Some(n) = max_degree {
        scenario.options.max_control_degree = n;
    }
    if let Some(words) = forms {
        let mut set = FormSet::default();
        for w in words {
            set.insert(parse_form(w)?);
        }
        scenario.options.forms = set;
        if max_degree.is_none() {
            scenario.options.max_control_degree = planner_core::MAX_CONTROL_DEGREE as u8;
        }
        let degree = scenario.options.max_control_degree;
        if !set.is_empty() && scenario.options.selected_forms().is_empty() && degree > 0 {
            bail!(
                "no form of --forms {} has a degree within --max-degree {degree}",
                words.join(",")
            );
        }
    }
    scenario.validate().context("invalid planning options")?;
    Ok(())
}

/// Loads a scenario file into the core's type, approximating polygons by `approx` (or each
/// obstacle's own method), and returns the obstacle shapes alongside for plotting.
pub fn load_scenario_shapes(
    path: &Path,
    approx: Option<Method>,
) -> Result<(Scenario, Vec<ObstacleShape>)> {
    let file = ScenarioFile::load(path)?;
    let shapes = file
        .obstacle_shapes(approx)
        .with_context(|| format!("in scenario {}", path.display()))?;
    let scenario = file
        .to_scenario_with(&shapes)
        .with_context(|| format!("in scenario {}", path.display()))?;
    Ok((scenario, shapes))
}

/// Loads a scenario file straight into the core's type.
pub fn load_scenario(path: &Path) -> Result<Scenario> {
    ScenarioFile::load(path)?
        .to_scenario()
        .with_context(|| format!("in scenario {}", path.display()))
}

/// The scenario file at `path` as a device is asked to plan it: the scenario, and the collision
/// bound with its execution model if the file sets one.
pub fn load_plan_request(
    path: &Path,
) -> Result<(
    planner_core::Scenario,
    Option<planner_core::wire::ChanceRequest>,
)> {
    let scenario = load_scenario(path)?;
    Ok((
        scenario,
        super::execution::load_execution(path)?.chance_request(),
    ))
}
