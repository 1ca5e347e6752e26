//! `needle cover`: a label map's segments as spheres a scenario can hold.

use super::cover::{cover_segment, CoverOptions, SegmentCover, DEFAULT_TIGHTNESS};
use super::label_map::{LabelMap, Segment};
use super::mesh::DEFAULT_VOXEL_MM;
use anyhow::{anyhow, bail, Result};
use planner_core::MAX_OBSTACLES;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;

/// What `needle cover` is asked: the image, which of its segments, the cover's options, and
/// whether the report is JSON (the `needle` binary reads these from its flags; `--out` and
/// `--scenario` are its own, since they write files rather than cover).
#[derive(Clone, Debug)]
pub struct CoverRequest {
    /// A label map: `.nrrd` (3D Slicer's `.seg.nrrd` too) or NIfTI `.nii` / `.nii.gz`; or a
    /// closed surface mesh (`.stl`, `.obj`), covered as the solid it bounds.
    pub image: PathBuf,
    /// The voxel edge a mesh is voxelised at (mm, above 0 and at most 10).
    pub voxel: f64,
    /// The unit a mesh's coordinates are in: mm (`None`), cm, m or um.
    pub unit: Option<String>,
    /// Cover these label values only (`None`: every label but 0).
    pub labels: Option<Vec<i64>>,
    /// Cover these segments only, by the names the file gives them (a `.seg.nrrd`).
    pub segments: Option<Vec<String>>,
    /// Grow every sphere by this much (mm, 0 to 100).
    pub margin: f64,
    /// The most spheres one segment's cover may take (at least 1).
    pub max_spheres: usize,
    /// The cover's volume at most this many times the segment's (dilated by the margin).
    pub tightness: f64,
    /// The report is JSON: no progress line, whatever stderr is.
    pub json: bool,
}

impl Default for CoverRequest {
    /// The command's defaults, for no image yet.
    fn default() -> Self {
        CoverRequest {
            image: PathBuf::new(),
            voxel: DEFAULT_VOXEL_MM,
            unit: None,
            labels: None,
            segments: None,
            margin: 0.0,
            max_spheres: MAX_OBSTACLES,
            tightness: DEFAULT_TIGHTNESS,
            json: false,
        }
    }
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
/// neither is given. Both at once, an empty list and a label or name given twice are refused:
/// each would otherwise cover something other than what was asked.
pub fn selected(
    map: &LabelMap,
    labels: Option<&[i64]>,
    segments: Option<&[String]>,
) -> Result<Vec<Segment>> {
    let present = map.segments();
    if present.is_empty() {
        bail!("the map has no labelled voxels (every voxel is 0)");
    }
    match (labels, segments) {
        (Some(_), Some(_)) => bail!(
            "labels and segments are both given: select by one of them (labels are the voxel \
             values, segments the names a .seg.nrrd gives them)"
        ),
        (Some(l), None) => {
            no_repeats(l, "labels", |x| x.to_string())?;
            l.iter().map(|&l| by_label(map, &present, l)).collect()
        }
        (None, Some(n)) => {
            no_repeats(n, "segments", |x| format!("{x:?}"))?;
            if map.named.is_empty() {
                bail!("the map names no segments (only a .seg.nrrd does): select by labels");
            }
            n.iter().map(|n| by_name(map, &present, n)).collect()
        }
        (None, None) => Ok(present),
    }
}

/// `list` (the `what` selected) is not empty and names nothing twice.
fn no_repeats<T: PartialEq>(list: &[T], what: &str, show: impl Fn(&T) -> String) -> Result<()> {
    if list.is_empty() {
        bail!(
            "the {what} list is empty, so it selects nothing: leave {what} out to cover every \
             segment, or list the ones to cover"
        );
    }
    for (n, x) in list.iter().enumerate() {
        if list[..n].contains(x) {
            bail!("{} is given twice in {what}: each is covered once", show(x));
        }
    }
    Ok(())
}

/// A segment the file names but no voxel holds (Slicer keeps a segment emptied by editing).
fn empty(s: &Segment) -> anyhow::Error {
    anyhow!(
        "segment {:?} (label {}) is empty: the file names it, but no voxel holds label {}",
        s.name,
        s.label,
        s.label
    )
}

fn by_label(map: &LabelMap, present: &[Segment], l: i64) -> Result<Segment> {
    if let Some(s) = present.iter().find(|s| s.label == l) {
        return Ok(s.clone());
    }
    match map.named.iter().find(|s| s.label == l) {
        Some(s) => Err(empty(s)),
        None => {
            let list: Vec<String> = present.iter().map(|s| s.label.to_string()).collect();
            Err(anyhow!(
                "label {l} is not in the map (its labels: {})",
                list.join(", ")
            ))
        }
    }
}

fn by_name(map: &LabelMap, present: &[Segment], n: &str) -> Result<Segment> {
    if let Some(s) = present.iter().find(|s| s.name == n) {
        return Ok(s.clone());
    }
    match map.named.iter().find(|s| s.name == n) {
        Some(s) => Err(empty(s)),
        None => {
            let names: Vec<String> = present.iter().map(|s| format!("{:?}", s.name)).collect();
            Err(anyhow!(
                "no segment is named {n:?} (segments with voxels: {})",
                names.join(", ")
            ))
        }
    }
}

/// The covers `a` asks for.
pub fn covers(a: &CoverRequest) -> Result<Vec<SegmentCover>> {
    let options = CoverOptions {
        margin_mm: a.margin,
        max_spheres: a.max_spheres,
        tightness: a.tightness,
    }
    .validated()?;
    let map = LabelMap::read_with(&a.image, a.voxel, a.unit.as_deref())?;
    let at = |e: anyhow::Error| anyhow!("{}: {e}", a.image.display());
    let chosen = selected(&map, a.labels.as_deref(), a.segments.as_deref()).map_err(at)?;
    if !a.json {
        crate::progress::enable();
    }
    let mut progress = crate::progress::Progress::new(format!("covering {}", a.image.display()));
    chosen
        .iter()
        .enumerate()
        .map(|(n, s)| {
            progress.step(n, chosen.len(), &format!("segment {:?}", s.name));
            cover_segment(&map, s, &options).map_err(at)
        })
        .collect()
}

/// What `needle cover --json` prints for `covers`.
pub fn report_json(a: &CoverRequest, covers: &[SegmentCover]) -> Result<serde_json::Value> {
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
pub fn cover_json(a: &CoverRequest) -> Result<serde_json::Value> {
    report_json(a, &covers(a)?)
}

/// The table `needle cover` prints for `covers` (`total` spheres).
pub fn table(a: &CoverRequest, covers: &[SegmentCover], total: usize) -> String {
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
    for c in covers.iter().filter(|c| !c.tight_enough) {
        let _ = writeln!(
            out,
            "{} (label {}): no cover of whole voxels tried is within a tightness of {}; this is \
             the tightest ({:.2} times its dilated volume)",
            c.name,
            c.label,
            a.tightness,
            1.0 + c.outside_dilated_ratio
        );
    }
    out
}

/// The spheres as `[[obstacles]]` tables, to append to a scenario file.
pub fn obstacles_toml(a: &CoverRequest, covers: &[SegmentCover]) -> String {
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
