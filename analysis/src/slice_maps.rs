//! The label maps a slice picture shows ([`super::slices`]), and where its three planes cross
//! (`needle plot --slice-at`).

use super::plot::PlotPath;
use anyhow::{anyhow, bail, Context, Result};
use needle_anatomy::command::selected;
use needle_anatomy::label_map::{LabelMap, Segment};
use needle_scenario::ScenarioFile;
use planner_core::Scenario;
use std::str::FromStr;

/// A label map of the scenario and the segments its `[[anatomy]]` entry covers.
pub struct SliceMap {
    /// The file, as the scenario names it (resolved from the scenario's folder).
    pub file: String,
    /// The map.
    pub map: LabelMap,
    /// The segments covered (filled in the slices); other labels are drawn faint.
    pub chosen: Vec<Segment>,
}

/// Where the three planes cross (`needle plot --slice-at`). The first three, when outside every
/// map, are moved into the nearest map's box of voxel centres; a typed point outside is an error.
#[derive(Clone, Debug, PartialEq)]
pub enum SliceAt {
    /// The best path's point of least clearance to the obstacles (the target when it has none).
    Closest,
    /// The target.
    Target,
    /// The entry.
    Entry,
    /// A point (RAS, mm).
    Point([f64; 3]),
}

impl FromStr for SliceAt {
    type Err = String;

    fn from_str(s: &str) -> Result<SliceAt, String> {
        match s {
            "closest" => return Ok(SliceAt::Closest),
            "target" => return Ok(SliceAt::Target),
            "entry" => return Ok(SliceAt::Entry),
            _ => {}
        }
        let v: Vec<f64> = s
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("expected closest, target, entry or X,Y,Z (RAS mm), got {s:?}"))?;
        match v[..] {
            [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(SliceAt::Point([x, y, z])),
            _ => Err(format!(
                "expected closest, target, entry or three finite numbers X,Y,Z (RAS mm), got {s:?}"
            )),
        }
    }
}

/// The label maps of `file`'s `[[anatomy]]` entries, each with its chosen segments.
pub fn slice_maps(file: &ScenarioFile) -> Result<Vec<SliceMap>> {
    file.anatomy
        .iter()
        .enumerate()
        .map(|(n, a)| {
            let path = file.relative(&a.file);
            let voxel = a.voxel_mm.unwrap_or(needle_anatomy::mesh::DEFAULT_VOXEL_MM);
            let map = LabelMap::read_with(&path, voxel, a.unit.as_deref())
                .with_context(|| format!("in anatomy[{n}]"))?;
            let chosen = selected(&map, a.labels.as_deref(), a.segments.as_deref())
                .map_err(|e| anyhow!("in anatomy[{n}]: {}: {e:#}", path.display()))?;
            Ok(SliceMap {
                file: path.display().to_string(),
                map,
                chosen,
            })
        })
        .collect()
}

/// The world box (RAS, mm) of a map's voxels, corners included.
pub(crate) fn map_box(map: &LabelMap) -> ([f64; 3], [f64; 3]) {
    grid_box(map, 0.5)
}

/// The world box (RAS, mm) of a map's voxel centres.
fn centres_box(map: &LabelMap) -> ([f64; 3], [f64; 3]) {
    grid_box(map, 0.0)
}

/// The world box of the grid grown by `grow` voxels on every side.
fn grid_box(map: &LabelMap, grow: f64) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for c in 0..8 {
        let g = [0, 1, 2].map(|k| {
            if c >> k & 1 == 1 {
                map.dims[k] as f64 - 1.0 + grow
            } else {
                -grow
            }
        });
        let w = map.world(g);
        for k in 0..3 {
            lo[k] = lo[k].min(w[k]);
            hi[k] = hi[k].max(w[k]);
        }
    }
    (lo, hi)
}

/// Whether `p` lies in the grid of `map` (within half a voxel of a voxel centre, along each axis).
fn in_grid(map: &LabelMap, p: [f64; 3]) -> bool {
    let g = map.grid(p);
    (0..3).all(|k| g[k] >= -0.5 && g[k] <= map.dims[k] as f64 - 0.5)
}

/// The label of `map` at world point `p` (nearest voxel), `None` outside its grid.
pub(crate) fn label_at(map: &LabelMap, p: [f64; 3]) -> Option<i64> {
    if !in_grid(map, p) {
        return None;
    }
    let g = map.grid(p).map(|x| x.round() as i64);
    Some(map.at(g[0], g[1], g[2]))
}

/// The point `at` names, inside at least one of `maps` (see [`SliceAt`]).
pub fn slice_point(
    at: &SliceAt,
    maps: &[SliceMap],
    scenario: &Scenario,
    best: Option<&PlotPath>,
) -> Result<[f64; 3]> {
    let f = |p: [f32; 3]| p.map(f64::from);
    let p = match at {
        SliceAt::Point(p) => *p,
        SliceAt::Target => f(scenario.target.position),
        SliceAt::Entry => f(scenario.entry.position),
        SliceAt::Closest => {
            let clearance = |q: &[f32; 3]| {
                scenario
                    .obstacles
                    .iter()
                    .map(|o| {
                        let d: f32 = (0..3).map(|k| (q[k] - o.center[k]).powi(2)).sum();
                        d.sqrt() - o.radius
                    })
                    .fold(f32::INFINITY, f32::min)
            };
            best.and_then(|b| {
                b.points
                    .iter()
                    .min_by(|a, b| clearance(a).total_cmp(&clearance(b)))
                    .map(|q| f(*q))
            })
            .unwrap_or_else(|| f(scenario.target.position))
        }
    };
    if maps.iter().any(|m| in_grid(&m.map, p)) {
        return Ok(p);
    }
    if !matches!(at, SliceAt::Point(_)) {
        // A point the user did not type (the path may pass beside the maps): the nearest point
        // of a map's box, so that each plane still cuts the anatomy.
        let nearest = maps
            .iter()
            .map(|m| {
                let (lo, hi) = centres_box(&m.map);
                std::array::from_fn(|k| p[k].clamp(lo[k], hi[k]))
            })
            .min_by(|a: &[f64; 3], b: &[f64; 3]| {
                let d = |q: &[f64; 3]| (0..3).map(|k| (q[k] - p[k]).powi(2)).sum::<f64>();
                d(a).total_cmp(&d(b))
            });
        if let Some(q) = nearest {
            return Ok(q);
        }
    }
    let extents: Vec<String> = maps
        .iter()
        .map(|m| {
            let (lo, hi) = map_box(&m.map);
            format!(
                "{}: x {:.1}..{:.1}, y {:.1}..{:.1}, z {:.1}..{:.1}",
                m.file, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]
            )
        })
        .collect();
    bail!(
        "the slice point ({:.2}, {:.2}, {:.2}) (RAS mm) lies outside every label map ({}): give \
         --slice-at X,Y,Z inside one",
        p[0],
        p[1],
        p[2],
        extents.join("; ")
    )
}
