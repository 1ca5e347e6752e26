//! `needle cover`: its flags, the label map's covers (`needle-anatomy`) printed, and with `--out`
//! written as `[[obstacles]]`, joined to `--scenario`'s text only when the two still make a
//! scenario.

use anyhow::{anyhow, Context, Result};
use needle_anatomy::command::{covers, obstacles_toml, report_json, table, CoverRequest};
use needle_anatomy::cover::{SegmentCover, DEFAULT_TIGHTNESS};
use needle_anatomy::mesh::DEFAULT_VOXEL_MM;
use needle_scenario::ScenarioFile;
use planner_core::MAX_OBSTACLES;
use std::path::{Path, PathBuf};

/// `needle cover`
#[derive(clap::Args, Clone, Debug)]
pub struct CoverArgs {
    /// A label map: `.nrrd` (3D Slicer's `.seg.nrrd` too) or NIfTI `.nii` / `.nii.gz`; or a
    /// closed surface mesh (`.stl`, `.obj`), covered as the solid it bounds.
    image: PathBuf,
    /// The voxel edge a mesh is voxelised at (mm, above 0 and at most 10).
    #[arg(long, default_value_t = DEFAULT_VOXEL_MM, allow_negative_numbers = true)]
    voxel: f64,
    /// The unit a mesh's coordinates are in: mm (the default), cm, m or um. A mesh whose extent
    /// is implausible for millimetres (under 1 mm or over 2 m) is refused unless this is given.
    #[arg(long, value_name = "UNIT")]
    unit: Option<String>,
    /// Cover these label values only (comma-separated; default: every label but 0).
    #[arg(
        long,
        value_delimiter = ',',
        conflicts_with = "segments",
        allow_negative_numbers = true
    )]
    labels: Option<Vec<i64>>,
    /// Cover these segments only, by the names the file gives them (a `.seg.nrrd`).
    #[arg(long, value_delimiter = ',')]
    segments: Option<Vec<String>>,
    /// Grow every sphere by this much (mm, 0 to 100): the segment dilated by it is covered.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    margin: f64,
    /// The most spheres one segment's cover may take (at least 1).
    #[arg(long, default_value_t = MAX_OBSTACLES)]
    max_spheres: usize,
    /// The cover's volume at most this many times the segment's (dilated by the margin): the
    /// fewest spheres that tight are taken. Where spheres holding whole voxels cannot be that
    /// tight (a segment a voxel or two thin), the tightest cover tried, and the command says so.
    #[arg(long, default_value_t = DEFAULT_TIGHTNESS)]
    tightness: f64,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Write the spheres as `[[obstacles]]` to this file: appended to `--scenario`'s text when
    /// given (a scenario that plans), else alone (to paste into one).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// The scenario the spheres join in `--out`.
    #[arg(long, value_name = "SCENARIO", requires = "out")]
    scenario: Option<PathBuf>,
}

impl CoverArgs {
    /// What the flags ask of the cover.
    fn request(&self) -> CoverRequest {
        CoverRequest {
            image: self.image.clone(),
            voxel: self.voxel,
            unit: self.unit.clone(),
            labels: self.labels.clone(),
            segments: self.segments.clone(),
            margin: self.margin,
            max_spheres: self.max_spheres,
            tightness: self.tightness,
            json: self.json,
        }
    }
}

/// Runs `needle cover`.
pub fn run_cover(args: &CoverArgs) -> Result<()> {
    let a = &args.request();
    let covers = covers(a)?;
    let total: usize = covers.iter().map(|c| c.spheres.len()).sum();
    if let Some(out) = &args.out {
        write_obstacles(out, args.scenario.as_deref(), a, &covers, total)?;
    }
    let text = if a.json {
        report_json(a, &covers)?.to_string() + "\n"
    } else {
        table(a, &covers, total)
    };
    print!("{text}");
    Ok(())
}

fn write_obstacles(
    out: &Path,
    scenario: Option<&Path>,
    a: &CoverRequest,
    covers: &[SegmentCover],
    total: usize,
) -> Result<()> {
    let spheres = obstacles_toml(a, covers);
    let text = match scenario {
        Some(base) => {
            let text = std::fs::read_to_string(base)
                .with_context(|| format!("cannot read {}", base.display()))?;
            let joined = text + &spheres;
            ScenarioFile::parse(&joined)
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
