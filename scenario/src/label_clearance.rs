//! A plan measured against the segmentation itself: the best path's least distance to the
//! voxels of the segments a scenario's `[[anatomy]]` entries cover (the cover is the optimiser's
//! smooth model and the device's obstacle list; the label map is the organ), and where the
//! target lies in the maps' voxels.

use super::file::ScenarioFile;
use anyhow::{anyhow, Result};
use needle_anatomy::command::selected;
use needle_anatomy::distance::least_distance;
use needle_anatomy::label_map::LabelMap;
use planner_core::check::{rebuild, sample_points};
use planner_core::model::kinematics::V3;
use planner_core::{FormOutcome, Scenario};

/// The points of `o`'s path at most `spacing` mm apart, entry to end (RAS, mm).
pub fn path_points(scenario: &Scenario, o: &FormOutcome, spacing: f32) -> Vec<[f64; 3]> {
    let geo = rebuild(scenario, o.form, &o.insertion, &o.segments);
    let mut pts = Vec::new();
    sample_points(&geo, spacing, |p: V3| {
        pts.push([p.x, p.y, p.z].map(f64::from));
    });
    pts
}

impl ScenarioFile {
    /// The least distance (mm) from the best path of `o` to the voxels of every segment the
    /// `[[anatomy]]` entries cover, sampled a quarter of the finest voxel apart; `None` without
    /// anatomy.
    pub fn label_map_clearance(&self, scenario: &Scenario, o: &FormOutcome) -> Result<Option<f64>> {
        let mut least: Option<f64> = None;
        for (n, a) in self.anatomy.iter().enumerate() {
            let at = |e: anyhow::Error| anyhow!("in anatomy[{n}]: {e:#}");
            let path = self.relative(&a.file);
            let voxel = a.voxel_mm.unwrap_or(needle_anatomy::mesh::DEFAULT_VOXEL_MM);
            let map = LabelMap::read_with(&path, voxel, a.unit.as_deref()).map_err(at)?;
            let labels: Vec<i64> = selected(&map, a.labels.as_deref(), a.segments.as_deref())
                .map_err(at)?
                .iter()
                .map(|s| s.label)
                .collect();
            let finest = (0..3)
                .map(|c| {
                    let m = &map.ijk_to_ras;
                    (m[0][c] * m[0][c] + m[1][c] * m[1][c] + m[2][c] * m[2][c]).sqrt()
                })
                .fold(f64::INFINITY, f64::min);
            let points = path_points(scenario, o, (0.25 * finest).max(0.01) as f32);
            let d = least_distance(&map, &labels, &points).map_err(at)?;
            least = Some(least.map_or(d, |l| l.min(d)));
        }
        Ok(least)
    }
}

impl ScenarioFile {
    /// Where the target lies: its RAS point (and the segment whose deepest point it is, when
    /// given as a label), and its voxel coordinates (i, j, k) in each `[[anatomy]]` map.
    pub fn target_lines(&self) -> Result<Vec<String>> {
        if self.anatomy.is_empty() && self.target.label.is_none() {
            return Ok(Vec::new());
        }
        let t = self.target_position()?.map(f64::from);
        let what = match self.target.label {
            Some(l) => format!("the deepest point of label {l}, "),
            None => String::new(),
        };
        let mut lines = vec![format!(
            "target: {what}RAS ({:.2}, {:.2}, {:.2}) mm",
            t[0], t[1], t[2]
        )];
        for a in &self.anatomy {
            let path = self.relative(&a.file);
            let voxel = a.voxel_mm.unwrap_or(needle_anatomy::mesh::DEFAULT_VOXEL_MM);
            let map = LabelMap::read_with(&path, voxel, a.unit.as_deref())?;
            let g = map.grid(t);
            let name = path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            lines.push(format!(
                "  voxel (i, j, k) ({:.2}, {:.2}, {:.2}) of {name}",
                g[0], g[1], g[2]
            ));
        }
        Ok(lines)
    }
}
