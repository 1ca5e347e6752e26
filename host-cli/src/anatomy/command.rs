//! `needle cover`: a label map's segments as spheres a scenario can hold.

use super::cover::{cover_segment, CoverOptions, SegmentCover, DEFAULT_TIGHTNESS};
use super::label_map::{LabelMap, Segment};
use super::mesh::DEFAULT_VOXEL_MM;
use anyhow::{anyhow, bail, Context, Result};
use planner_core::MAX_OBSTACLES;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// `needle cover`
#[derive(clap::Args, Clone, Debug)]
pub struct CoverArgs {
    /// A label map: `.nrrd` (3D Slicer's `.seg.nrrd` too) or NIfTI `.nii` / `.nii.gz`; or a
    /// closed surface mesh (`.stl`, `.obj`), covered as the solid it bounds.
    pub image: PathBuf,
    /// The voxel edge a mesh is voxelised at (mm).
    #[arg(long, default_value_t = DEFAULT_VOXEL_MM)]
    pub voxel: f64,
    /// Cover these label values only (comma-separated; default: every label but 0).
    #[arg(long, value_delimiter = ',', conflicts_with = "segments")]
    pub labels: Vec<i64>,
    /// Cover these segments only, by the names the file gives them (a `.seg.nrrd`).
    #[arg(long, value_delimiter = ',')]
    pub segments: Vec<String>,
    /// Grow every sphere by this much (mm): the segment dilated by it is covered.
    #[arg(long, default_value_t = 0.0)]
    pub margin: f64,
    /// The most spheres one segment's cover may take.
    #[arg(long, default_value_t = MAX_OBSTACLES)]
    pub max_spheres: usize,
    /// Split a sphere while it holds more than this many times its voxels' volume (and a split
    /// makes the cover smaller). A cube in its sphere is 2.7 times.
    #[arg(long, default_value_t = DEFAULT_TIGHTNESS)]
    pub tightness: f64,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Write the spheres as `[[obstacles]]` to this file: appended to `--scenario`'s text when
    /// given (a scenario that plans), else alone (to paste into one).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// The scenario the spheres join in `--out`.
    #[arg(long, value_name = "SCENARIO", requires = "out")]
    pub scenario: Option<PathBuf>,
}

/// What `needle cover --json` prints.
#[derive(Serialize)]
struct CoverReport<'a> {
    file: String,
    frame: &'static str,
    margin_mm: f64,
    segments: &'a [SegmentCover],
    spheres: usize,
}

/// The segments of `map` that `labels` or `segments` (names) select; every segment present when
/// both are empty.
pub fn selected(map: &LabelMap, labels: &[i64], segments: &[String]) -> Result<Vec<Segment>> {
    let present = map.segments();
    let label_list = || {
        present
            .iter()
            .map(|s| s.label.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    if present.is_empty() {
        bail!("the map has no labelled voxels (every voxel is 0)");
    }
    // A segment the file names but no voxel holds (Slicer keeps a segment emptied by editing).
    let empty = |s: &Segment| {
        anyhow!(
            "segment {:?} (label {}) is empty: the file names it, but no voxel holds label {}",
            s.name,
            s.label,
            s.label
        )
    };
    if !labels.is_empty() {
        return labels
            .iter()
            .map(|&l| {
                if let Some(s) = present.iter().find(|s| s.label == l) {
                    return Ok(s.clone());
                }
                match map.named.iter().find(|s| s.label == l) {
                    Some(s) => Err(empty(s)),
                    None => Err(anyhow!(
                        "label {l} is not in the map (its labels: {})",
                        label_list()
                    )),
                }
            })
            .collect();
    }
    if !segments.is_empty() {
        if map.named.is_empty() {
            bail!("the map names no segments (only a .seg.nrrd does): select by --labels");
        }
        let names = || {
            present
                .iter()
                .map(|s| format!("{:?}", s.name))
                .collect::<Vec<_>>()
                .join(", ")
        };
        return segments
            .iter()
            .map(|n| {
                if let Some(s) = present.iter().find(|s| &s.name == n) {
                    return Ok(s.clone());
                }
                match map.named.iter().find(|s| &s.name == n) {
                    Some(s) => Err(empty(s)),
                    None => Err(anyhow!(
                        "no segment is named {n:?} (segments with voxels: {})",
                        names()
                    )),
                }
            })
            .collect();
    }
    Ok(present)
}

/// The covers `a` asks for.
pub fn covers(a: &CoverArgs) -> Result<Vec<SegmentCover>> {
    let map = LabelMap::read_with(&a.image, a.voxel)?;
    let at = |e: anyhow::Error| anyhow!("{}: {e}", a.image.display());
    let options = CoverOptions {
        margin_mm: a.margin,
        max_spheres: a.max_spheres.max(1),
        tightness: a.tightness,
    };
    selected(&map, &a.labels, &a.segments)
        .map_err(at)?
        .iter()
        .map(|s| cover_segment(&map, s, &options).map_err(at))
        .collect()
}

/// What `needle cover --json` prints for `covers`.
fn report_json(a: &CoverArgs, covers: &[SegmentCover]) -> Result<serde_json::Value> {
    let report = CoverReport {
        file: a.image.display().to_string(),
        frame: "RAS",
        margin_mm: a.margin,
        segments: covers,
        spheres: covers.iter().map(|c| c.spheres.len()).sum(),
    };
    Ok(serde_json::to_value(&report)?)
}

/// The JSON report of `needle cover` for `a` (the Python package's `cover`), without writing
/// `--out`.
pub fn cover_json(a: &CoverArgs) -> Result<serde_json::Value> {
    report_json(a, &covers(a)?)
}

/// Runs `needle cover`.
pub fn run_cover(a: &CoverArgs) -> Result<()> {
    let covers = covers(a)?;
    let total: usize = covers.iter().map(|c| c.spheres.len()).sum();
    if let Some(out) = &a.out {
        write_obstacles(out, a, &covers, total)?;
    }
    let text = if a.json {
        report_json(a, &covers)?.to_string() + "\n"
    } else {
        table(a, &covers, total)
    };
    print!("{text}");
    Ok(())
}

fn table(a: &CoverArgs, covers: &[SegmentCover], total: usize) -> String {
    let mut out = format!(
        "sphere cover of {} (RAS, mm; margin {} mm)\n{:<24}{:>7}{:>9}{:>13}{:>9}{:>10}{:>11}\n",
        a.image.display(),
        a.margin,
        "segment",
        "label",
        "voxels",
        "volume mm3",
        "spheres",
        "outside",
        "farthest"
    );
    for c in covers {
        let _ = writeln!(
            out,
            "{:<24}{:>7}{:>9}{:>13.1}{:>9}{:>9.0}%{:>8.2} mm",
            c.name,
            c.label,
            c.voxels,
            c.volume_mm3,
            c.spheres.len(),
            100.0 * c.outside_ratio,
            c.farthest_mm
        );
    }
    let _ = writeln!(
        out,
        "{total} spheres; every voxel of each segment lies inside its cover (checked corner by corner)"
    );
    out
}

/// The spheres as `[[obstacles]]` tables.
fn obstacles_toml(a: &CoverArgs, covers: &[SegmentCover]) -> String {
    let mut out = format!(
        "\n# Sphere cover of {} (needle cover, margin {} mm, RAS mm)\n",
        a.image.display(),
        a.margin
    );
    for c in covers {
        let _ = writeln!(out, "# {} (label {})", c.name, c.label);
        for s in &c.spheres {
            let _ = writeln!(
                out,
                "[[obstacles]]\ncenter = [{}, {}, {}]\nradius = {}\n",
                s.center[0] as f32, s.center[1] as f32, s.center[2] as f32, s.radius as f32
            );
        }
    }
    out
}

fn write_obstacles(out: &Path, a: &CoverArgs, covers: &[SegmentCover], total: usize) -> Result<()> {
    let spheres = obstacles_toml(a, covers);
    let text = match &a.scenario {
        Some(base) => {
            let text = std::fs::read_to_string(base)
                .with_context(|| format!("cannot read {}", base.display()))?;
            let joined = text + &spheres;
            crate::scenario::file::ScenarioFile::parse(&joined)
                .and_then(|f| f.to_scenario())
                .map_err(|e| {
                    anyhow!(
                        "{} with the cover's {total} spheres is not a scenario: {e:#}",
                        base.display()
                    )
                })?;
            joined
        }
        None => spheres,
    };
    std::fs::write(out, text).with_context(|| format!("cannot write {}", out.display()))
}
