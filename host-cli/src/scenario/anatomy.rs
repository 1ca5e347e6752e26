//! `[[anatomy]]` entries of a scenario file: each label map's segments covered by spheres
//! (`needle cover`'s cover), added to the obstacles.

use super::file::{AnatomyFile, ScenarioFile};
use super::shapes::ObstacleShape;
use crate::anatomy::command::selected;
use crate::anatomy::cover::{cover_segment, CoverOptions, DEFAULT_TIGHTNESS};
use crate::anatomy::label_map::LabelMap;
use anyhow::{anyhow, bail, Result};
use planner_core::model::scenario::Obstacle;
use planner_core::MAX_OBSTACLES;

impl ScenarioFile {
    /// The spheres of every `[[anatomy]]` entry, one shape per entry; their indices follow the
    /// `[[obstacles]]`' ones.
    pub fn anatomy_shapes(&self, plane: bool) -> Result<Vec<ObstacleShape>> {
        if self.anatomy.is_empty() {
            return Ok(Vec::new());
        }
        if plane {
            bail!("anatomy is 3-D: leave planner.plane out");
        }
        // Once for every entry: a target given as a label reads its label map.
        let ends = [self.entry_position()?, self.target_position()?];
        self.anatomy
            .iter()
            .enumerate()
            .map(|(n, a)| {
                let circles = self
                    .anatomy_spheres(a, ends)
                    .map_err(|e| anyhow!("in anatomy[{n}]: {e:#}"))?;
                Ok(ObstacleShape {
                    index: self.obstacles.len() + n,
                    polygon: None,
                    circles,
                })
            })
            .collect()
    }

    /// The spheres of entry `a`; `ends` (entry, target) must lie outside them.
    fn anatomy_spheres(&self, a: &AnatomyFile, ends: [[f32; 3]; 2]) -> Result<Vec<Obstacle>> {
        let path = self.relative(&a.file);
        let options = CoverOptions {
            margin_mm: a.margin_mm.unwrap_or(0.0),
            max_spheres: a.max_spheres.unwrap_or(MAX_OBSTACLES),
            tightness: a.tightness.unwrap_or(DEFAULT_TIGHTNESS),
        }
        .validated()?;
        let voxel = a.voxel_mm.unwrap_or(crate::anatomy::mesh::DEFAULT_VOXEL_MM);
        let map = LabelMap::read_with(&path, voxel, a.unit.as_deref())?;
        let at = |e: anyhow::Error| anyhow!("{}: {e:#}", path.display());
        let [entry, target] = ends;
        let mut out = Vec::new();
        let chosen = selected(&map, a.labels.as_deref(), a.segments.as_deref()).map_err(at)?;
        for segment in chosen {
            let cover = cover_segment(&map, &segment, &options).map_err(at)?;
            for s in cover.spheres {
                let inside = |p: [f32; 3]| {
                    let d: f64 = (0..3)
                        .map(|k| (f64::from(p[k]) - s.center[k]).powi(2))
                        .sum();
                    d.sqrt() <= s.radius
                };
                for (what, p) in [("entry", entry), ("target", target)] {
                    if inside(p) {
                        bail!(
                            "the {what} lies inside the cover of segment {:?} of {}: select the \
                             structures to avoid (labels, segments), not the one that holds the {what}",
                            segment.name,
                            path.display()
                        );
                    }
                }
                out.push(Obstacle {
                    center: s.center.map(|v| v as f32),
                    radius: s.radius as f32,
                });
            }
        }
        Ok(out)
    }
}
