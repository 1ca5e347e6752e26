//! A true path judged against the segmentation itself: whether it entered a voxel of a segment
//! the scenario's `[[anatomy]]` entries cover. The cover is the planner's and the device's model
//! of the organ; the simulated insertions are judged against the organ.

use super::file::ScenarioFile;
use anyhow::{anyhow, Result};
use needle_anatomy::command::selected;
use needle_anatomy::label_map::LabelMap;

/// The voxels of the covered segments, map by map.
pub struct VoxelJudge {
    maps: Vec<(LabelMap, Vec<i64>)>,
    /// The spacing of the points looked at along a path (mm): a tenth of the finest voxel.
    step_mm: f64,
}

impl ScenarioFile {
    /// The judge of the `[[anatomy]]` entries' segments; `None` without anatomy.
    pub fn voxel_judge(&self) -> Result<Option<VoxelJudge>> {
        if self.anatomy.is_empty() {
            return Ok(None);
        }
        let mut maps = Vec::new();
        let mut finest = f64::INFINITY;
        for (n, a) in self.anatomy.iter().enumerate() {
            let at = |e: anyhow::Error| anyhow!("in anatomy[{n}]: {e:#}");
            let voxel = a.voxel_mm.unwrap_or(needle_anatomy::mesh::DEFAULT_VOXEL_MM);
            let map = LabelMap::read_with(&self.relative(&a.file), voxel, a.unit.as_deref())
                .map_err(at)?;
            let labels: Vec<i64> = selected(&map, a.labels.as_deref(), a.segments.as_deref())
                .map_err(at)?
                .iter()
                .map(|s| s.label)
                .collect();
            let [r0, r1, r2] = &map.ijk_to_ras;
            for c in 0..3 {
                finest = finest.min((r0[c] * r0[c] + r1[c] * r1[c] + r2[c] * r2[c]).sqrt());
            }
            maps.push((map, labels));
        }
        Ok(Some(VoxelJudge {
            maps,
            step_mm: (0.1 * finest).max(0.01),
        }))
    }
}

impl VoxelJudge {
    /// Whether the path through `points` (joined by straight pieces: a true path's points lie at
    /// most 1 mm apart, where an arc of the needle's radius strays from its chord by
    /// thousandths of a millimetre) enters a voxel of a covered segment.
    pub fn entered(&self, points: &[[f32; 3]]) -> bool {
        let p = |q: &[f32; 3]| q.map(f64::from);
        if let Some(first) = points.first() {
            if self.inside(p(first)) {
                return true;
            }
        }
        points.windows(2).any(|w| {
            let (a, b) = (p(&w[0]), p(&w[1]));
            let length = (0..3).map(|k| (b[k] - a[k]).powi(2)).sum::<f64>().sqrt();
            let n = (length / self.step_mm).ceil().max(1.0) as usize;
            (1..=n).any(|i| {
                let t = i as f64 / n as f64;
                self.inside([0, 1, 2].map(|k| a[k] + t * (b[k] - a[k])))
            })
        })
    }

    /// Whether `p` (RAS, mm) lies in a voxel of a covered segment.
    fn inside(&self, p: [f64; 3]) -> bool {
        self.maps.iter().any(|(map, labels)| {
            let mut index = 0usize;
            let mut stride = 1usize;
            for (g, &n) in map.grid(p).iter().zip(&map.dims) {
                let v = g.round();
                if !(v >= 0.0 && v < n as f64) {
                    return false;
                }
                index += v as usize * stride;
                stride *= n;
            }
            map.labels.get(index).is_some_and(|l| labels.contains(l))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cube of 1 mm voxels (labels 1, centres 5 to 14 mm) on a 0.5 x 0.5 x 2 mm grid
    /// elsewhere too: a path through it enters, one past its face by a tenth of a voxel does
    /// not, one crossing a corner between two far points does, a label not chosen is not seen.
    #[test]
    fn a_path_enters_the_voxels_it_crosses() {
        let dims = [20usize, 20, 20];
        let labels = (0..8000)
            .map(|c| {
                let v = [c % 20, c / 20 % 20, c / 400];
                i64::from(v.iter().all(|x| (5..15).contains(x)))
            })
            .collect();
        let map = LabelMap {
            dims,
            labels,
            ijk_to_ras: [
                [1.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ],
            named: Vec::new(),
        };
        let judge = |chosen: Vec<i64>| VoxelJudge {
            maps: vec![(map.clone(), chosen)],
            step_mm: 0.25,
        };
        let j = judge(vec![1]);
        assert!(j.entered(&[[0.0, 9.0, 9.0], [1.0, 9.0, 9.0], [30.0, 9.0, 9.0]]));
        // The cube's face is at 14.5 mm.
        assert!(!j.entered(&[[14.6, 0.0, 9.0], [14.6, 19.0, 9.0]]));
        assert!(j.entered(&[[14.4, 0.0, 9.0], [14.4, 19.0, 9.0]]));
        // Two points far apart, the piece between them through the corner region.
        assert!(j.entered(&[[0.0, 0.0, 0.0], [19.0, 19.0, 19.0]]));
        assert!(!judge(vec![2]).entered(&[[0.0, 9.0, 9.0], [30.0, 9.0, 9.0]]));
        assert!(!j.entered(&[]));
    }
}
