//! `needle approx`.

use super::output::{title_of, write};
use crate::plot::{scene_svg, Scene};
use anyhow::{Context, Result};
use needle_report::json::write_sorted;
use needle_scenario::approx::Method;
use needle_scenario::ScenarioFile;
use planner_core::model::scenario::Obstacle;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::io::Write;
use std::path::PathBuf;

/// What `needle approx` is asked.
#[derive(Clone, Debug)]
pub struct ApproxOptions {
    /// Scenario file with polygon obstacles.
    pub file: PathBuf,
    /// The method for every polygon (`None`: each obstacle's own `approx`).
    pub method: Option<Method>,
    /// Print one JSON object instead of the table.
    pub json: bool,
    /// Draw the polygons and their circles (SVG).
    pub plot: Option<PathBuf>,
}

/// The `needle approx --json` object: each polygon obstacle's circles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ApproxJson {
    /// The polygon obstacles, in file order (circle obstacles are left out).
    pub obstacles: Vec<ApproximationJson>,
}

/// One polygon obstacle's covering circles and what they cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ApproximationJson {
    /// Index in the file's `[[obstacles]]`.
    pub index: usize,
    /// The method's name.
    pub method: String,
    /// Area of the polygon (mm²).
    pub polygon_area: f64,
    /// Area of the circles' union (mm²).
    pub covered_area: f64,
    /// Area the circles add beyond the polygon (mm²).
    pub added_area: f64,
    /// The circles handed to the planner.
    pub circles: Vec<CircleJson>,
}

/// A circle (sphere) obstacle as the planner sees it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CircleJson {
    /// Centre (mm).
    pub center: [f64; 3],
    /// Radius (mm).
    pub radius: f64,
}

impl CircleJson {
    fn of(c: &Obstacle) -> CircleJson {
        CircleJson {
            center: c.center.map(f64::from),
            radius: f64::from(c.radius),
        }
    }
}

impl fmt::Display for ApproxJson {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_sorted(self, f)
    }
}

/// Runs `needle approx`.
pub fn run_approx(a: &ApproxOptions) -> Result<()> {
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
        out.push(ApproximationJson {
            index: s.index,
            method: ap.method.name().to_string(),
            polygon_area: ap.polygon_area,
            covered_area: ap.covered_area,
            added_area: ap.added_area(),
            circles: s.circles.iter().map(CircleJson::of).collect(),
        });
    }
    if a.json {
        writeln!(std::io::stdout(), "{}", ApproxJson { obstacles: out })?;
    } else {
        write!(std::io::stdout(), "{text}")?;
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
