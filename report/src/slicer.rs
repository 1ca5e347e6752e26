//! `needle plan|send|simulate --export DIR`: the plan (and simulated paths) as files 3D Slicer
//! opens. The path is a markups `Curve`
//! (points at most 1 mm apart) and the entry and target a markups point list, both in RAS; the
//! obstacles are one model (legacy VTK PolyData, triangulated spheres) in LPS, the coordinate
//! system Slicer assumes for a model file that does not name one.

use super::json::path_points;
use anyhow::{Context, Result};
use needle_anatomy::markups::FileOut;
use planner_core::report::FormOutcome;
use planner_core::{PlanReport, Scenario};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Rings and segments of a sphere's mesh.
const RINGS: usize = 10;
const SEGMENTS: usize = 20;

/// Writes the export of `report` into `dir` (made if missing); returns the files written.
pub fn export(dir: &Path, scenario: &Scenario, report: &PlanReport) -> Result<Vec<PathBuf>> {
    export_best(dir, scenario, report.best())
}

/// [`export`] for the path `best` (none: the entry, target and obstacles alone).
pub fn export_best(
    dir: &Path,
    scenario: &Scenario,
    best: Option<&FormOutcome>,
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut written = Vec::new();
    let mut write = |name: &str, text: String| -> Result<()> {
        let path = dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
        written.push(path);
        Ok(())
    };
    let points = [
        ("entry".to_string(), scenario.entry.position),
        ("target".to_string(), scenario.target.position),
    ];
    write(
        "entry-target.mrk.json",
        serde_json::to_string_pretty(&FileOut::one("Fiducial", "entry and target", &points))?,
    )?;
    if let Some(best) = best {
        let path: Vec<(String, [f32; 3])> = path_points(scenario, best)
            .into_iter()
            .enumerate()
            .map(|(n, p)| (format!("p{}", n + 1), p))
            .collect();
        let name = format!("needle plan {}", best.form.word().as_str());
        write(
            "plan.mrk.json",
            serde_json::to_string_pretty(&FileOut::one("Curve", &name, &path))?,
        )?;
    }
    if !scenario.obstacles.is_empty() {
        write("obstacles.vtk", spheres_vtk(scenario))?;
    }
    Ok(written)
}

/// Polylines (each a path's points, RAS) as one legacy VTK PolyData model, LPS: Slicer shows
/// them as lines.
pub fn polylines_vtk(title: &str, lines: &[&[[f32; 3]]]) -> String {
    let lines: Vec<&[[f32; 3]]> = lines.iter().copied().filter(|l| l.len() >= 2).collect();
    let count: usize = lines.iter().map(|l| l.len()).sum();
    let mut out = format!(
        "# vtk DataFile Version 3.0\n{title} SPACE=LPS\nASCII\nDATASET POLYDATA\nPOINTS {count} float\n"
    );
    for p in lines.iter().flat_map(|l| l.iter()) {
        let _ = writeln!(out, "{} {} {}", -p[0], -p[1], p[2]);
    }
    let _ = writeln!(out, "LINES {} {}", lines.len(), count + lines.len());
    let mut at = 0usize;
    for l in &lines {
        let _ = write!(out, "{}", l.len());
        for k in 0..l.len() {
            let _ = write!(out, " {}", at + k);
        }
        let _ = writeln!(out);
        at += l.len();
    }
    out
}

/// Every obstacle as a triangulated sphere, in one legacy VTK PolyData file, LPS.
fn spheres_vtk(scenario: &Scenario) -> String {
    let mut points = Vec::new();
    let mut triangles = Vec::new();
    for ob in &scenario.obstacles {
        let base = points.len();
        let c = ob.center.map(f64::from);
        let r = f64::from(ob.radius);
        points.push([c[0], c[1], c[2] + r]);
        for ring in 1..RINGS {
            let polar = std::f64::consts::PI * ring as f64 / RINGS as f64;
            for seg in 0..SEGMENTS {
                let az = std::f64::consts::TAU * seg as f64 / SEGMENTS as f64;
                points.push([
                    c[0] + r * polar.sin() * az.cos(),
                    c[1] + r * polar.sin() * az.sin(),
                    c[2] + r * polar.cos(),
                ]);
            }
        }
        points.push([c[0], c[1], c[2] - r]);
        let at = |ring: usize, seg: usize| base + 1 + (ring - 1) * SEGMENTS + seg % SEGMENTS;
        let south = base + 1 + (RINGS - 1) * SEGMENTS;
        for seg in 0..SEGMENTS {
            triangles.push([base, at(1, seg), at(1, seg + 1)]);
            for ring in 1..RINGS - 1 {
                let (a, b) = (at(ring, seg), at(ring, seg + 1));
                let (d, e) = (at(ring + 1, seg), at(ring + 1, seg + 1));
                triangles.push([a, d, e]);
                triangles.push([a, e, b]);
            }
            triangles.push([at(RINGS - 1, seg), south, at(RINGS - 1, seg + 1)]);
        }
    }
    let mut out = format!(
        "# vtk DataFile Version 3.0\nneedle-planner obstacles SPACE=LPS\nASCII\nDATASET POLYDATA\n\
         POINTS {} float\n",
        points.len()
    );
    for p in &points {
        // RAS to LPS.
        let _ = writeln!(out, "{} {} {}", -p[0] as f32, -p[1] as f32, p[2] as f32);
    }
    let _ = writeln!(out, "POLYGONS {} {}", triangles.len(), 4 * triangles.len());
    for t in &triangles {
        let _ = writeln!(out, "3 {} {} {}", t[0], t[1], t[2]);
    }
    out
}
