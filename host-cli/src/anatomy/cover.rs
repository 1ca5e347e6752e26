//! Conservative sphere covers of a label map's segments.
//!
//! Every voxel of a segment (the whole cube, its eight corners) lies inside one sphere of its
//! cover, and the cover is dilated by the margin. The cover is a bounding-sphere hierarchy, the
//! seed paper's "segmented" circles in 3-D: one sphere around the whole segment (centred on the
//! box of its voxels' corners, its radius the farthest corner), then the sphere that encloses
//! the most volume beyond its own voxels is split in two (its voxels halved at the median along
//! their longest extent) for as long as a sphere is looser than `tightness` times the volume of
//! its voxels and splitting it makes the cover smaller. A ball stays one sphere; a thin tube
//! becomes a chain.

use super::label_map::{LabelMap, Segment};
use anyhow::{bail, Result};
use serde::Serialize;

/// The tightness a cover keeps when none is given: a cube in its sphere is 2.7 times its volume.
pub const DEFAULT_TIGHTNESS: f64 = 3.0;

/// A sphere of a cover (RAS, mm).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sphere {
    /// Centre (mm).
    pub center: [f64; 3],
    /// Radius (mm), the margin included.
    pub radius: f64,
}

impl Sphere {
    fn volume(&self) -> f64 {
        4.0 / 3.0 * std::f64::consts::PI * self.radius.powi(3)
    }

    fn contains(&self, p: [f64; 3]) -> bool {
        dist(self.center, p) <= self.radius
    }
}

/// How a cover is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoverOptions {
    /// Every sphere grows by this (mm, ≥ 0): the voxels dilated by it are covered.
    pub margin_mm: f64,
    /// The most spheres one segment's cover may have.
    pub max_spheres: usize,
    /// A sphere looser than this many times its voxels' volume is split while that helps.
    pub tightness: f64,
}

/// One segment's cover and how tight it is.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SegmentCover {
    /// The segment's name.
    pub name: String,
    /// Its label value.
    pub label: i64,
    /// Its voxels.
    pub voxels: usize,
    /// Its volume (mm³).
    pub volume_mm3: f64,
    /// The cover.
    pub spheres: Vec<Sphere>,
    /// The cover's volume outside the segment over the segment's volume (sampled at half a
    /// voxel's spacing).
    pub outside_ratio: f64,
    /// The largest distance from a point of the cover to the segment's nearest voxel centre
    /// (mm, sampled at the voxel centres).
    pub farthest_mm: f64,
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The eight corner offsets of a voxel in the world (mm).
fn corner_offsets(map: &LabelMap) -> [[f64; 3]; 8] {
    let a = &map.ijk_to_ras;
    std::array::from_fn(|n| {
        let d = [0, 1, 2].map(|k| if n >> k & 1 == 1 { 0.5 } else { -0.5 });
        [0, 1, 2].map(|r| a[r][0] * d[0] + a[r][1] * d[1] + a[r][2] * d[2])
    })
}

fn centre_of(map: &LabelMap, v: &[i64; 3]) -> [f64; 3] {
    map.world(v.map(|x| x as f64))
}

/// The sphere around the corners of `voxels` (no margin), centred on their bounding box.
fn enclosing(map: &LabelMap, voxels: &[[i64; 3]], corners: &[[f64; 3]; 8]) -> Sphere {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for v in voxels {
        let c = centre_of(map, v);
        for off in corners {
            for k in 0..3 {
                lo[k] = lo[k].min(c[k] + off[k]);
                hi[k] = hi[k].max(c[k] + off[k]);
            }
        }
    }
    let center = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let mut radius = 0.0f64;
    for v in voxels {
        let c = centre_of(map, v);
        for off in corners {
            radius = radius.max(dist(center, [c[0] + off[0], c[1] + off[1], c[2] + off[2]]));
        }
    }
    Sphere { center, radius }
}

/// Grid coordinates of voxels.
type Voxels = Vec<[i64; 3]>;

/// Relative differences below this are ties: the same anatomy in a float32 affine (NIfTI's) and
/// a float64 one (NRRD's) must give the same cover, so no decision may hang on rounding.
const TIE: f64 = 1e-6;

/// Splits `voxels` in two at the median along the grid axis of their longest world extent (the
/// first such axis when extents tie); `None` when they cannot be split (one voxel, or all in one
/// place along every axis).
fn halves(map: &LabelMap, voxels: &[[i64; 3]]) -> Option<(Voxels, Voxels)> {
    let spacing = map.spacing();
    let mut axes: Vec<(f64, usize)> = (0..3)
        .map(|k| {
            let (lo, hi) = voxels
                .iter()
                .fold((i64::MAX, i64::MIN), |(l, h), v| (l.min(v[k]), h.max(v[k])));
            ((hi - lo) as f64 * spacing[k], k)
        })
        .collect();
    let longest = axes.iter().map(|a| a.0).fold(0.0, f64::max);
    axes.retain(|a| a.0 >= longest * (1.0 - TIE));
    let (extent, k) = axes[0];
    if extent == 0.0 {
        return None;
    }
    let mut sorted = voxels.to_vec();
    sorted.sort_by_key(|v| (v[k], v[0], v[1], v[2]));
    let mid = sorted.len() / 2;
    // Keep voxels of one grid slice together.
    let cut = std::iter::once(mid)
        .chain((1..sorted.len()).flat_map(|d| [mid.saturating_sub(d), mid + d]))
        .find(|&m| m > 0 && m < sorted.len() && sorted[m - 1][k] != sorted[m][k])?;
    let second = sorted.split_off(cut);
    Some((sorted, second))
}

struct Leaf {
    voxels: Vec<[i64; 3]>,
    sphere: Sphere,
    /// The sphere's volume over its voxels' volume.
    looseness: f64,
    /// Splitting it was tried and made the cover no smaller.
    settled: bool,
}

fn leaf(map: &LabelMap, voxels: Vec<[i64; 3]>, corners: &[[f64; 3]; 8]) -> Leaf {
    let sphere = enclosing(map, &voxels, corners);
    let own = voxels.len() as f64 * map.voxel_volume();
    Leaf {
        looseness: sphere.volume() / own,
        sphere,
        voxels,
        settled: false,
    }
}

/// The spheres (no margin) that cover `voxels`, as the module describes.
fn hierarchy(
    map: &LabelMap,
    voxels: Vec<[i64; 3]>,
    o: &CoverOptions,
    name: &str,
) -> Result<Vec<Sphere>> {
    let corners = corner_offsets(map);
    let mut leaves = vec![leaf(map, voxels, &corners)];
    loop {
        let worst = leaves
            .iter()
            .enumerate()
            .filter(|(_, l)| !l.settled && l.looseness > o.tightness * (1.0 + TIE))
            .max_by(|a, b| {
                let excess = |l: &Leaf| l.sphere.volume() * (1.0 - 1.0 / l.looseness);
                excess(a.1).total_cmp(&excess(b.1))
            })
            .map(|(n, _)| n);
        let Some(n) = worst else { break };
        let Some((a, b)) = halves(map, &leaves[n].voxels) else {
            leaves[n].settled = true;
            continue;
        };
        let (a, b) = (leaf(map, a, &corners), leaf(map, b, &corners));
        if a.sphere.volume() + b.sphere.volume() >= leaves[n].sphere.volume() * (1.0 - TIE) {
            leaves[n].settled = true;
            continue;
        }
        if leaves.len() == o.max_spheres {
            bail!(
                "covering {name} within a tightness of {} needs more than {} spheres \
                 (--max-spheres): raise it, or loosen --tightness",
                o.tightness,
                o.max_spheres
            );
        }
        leaves[n] = a;
        leaves.push(b);
    }
    Ok(leaves.into_iter().map(|l| l.sphere).collect())
}

/// The cover of `segment` in `map`.
pub fn cover_segment(map: &LabelMap, segment: &Segment, o: &CoverOptions) -> Result<SegmentCover> {
    if !(o.margin_mm >= 0.0 && o.margin_mm.is_finite()) {
        bail!("the margin must be a number of millimetres, 0 or more");
    }
    if !(o.tightness > 1.0 && o.tightness.is_finite()) {
        bail!("the tightness must be a number above 1");
    }
    let voxels = map.voxels_of(segment.label);
    if voxels.is_empty() {
        bail!(
            "segment {:?} (label {}) has no voxels",
            segment.name,
            segment.label
        );
    }
    let name = format!("{:?} (label {})", segment.name, segment.label);
    let mut spheres = hierarchy(map, voxels.clone(), o, &name)?;
    for s in &mut spheres {
        s.radius += o.margin_mm;
    }
    let uncovered = uncovered_corners(map, &voxels, &spheres);
    if uncovered > 0 {
        bail!("internal error: the cover of {name} leaves {uncovered} voxel corners out");
    }
    let (outside_ratio, farthest_mm) = tightness(map, segment.label, &voxels, &spheres);
    Ok(SegmentCover {
        name: segment.name.clone(),
        label: segment.label,
        voxels: voxels.len(),
        volume_mm3: voxels.len() as f64 * map.voxel_volume(),
        spheres,
        outside_ratio,
        farthest_mm,
    })
}

/// The voxel corners of `voxels` inside no sphere of `spheres` (checked one by one).
pub fn uncovered_corners(map: &LabelMap, voxels: &[[i64; 3]], spheres: &[Sphere]) -> usize {
    let corners = corner_offsets(map);
    voxels
        .iter()
        .flat_map(|v| {
            let c = centre_of(map, v);
            corners.map(|off| [c[0] + off[0], c[1] + off[1], c[2] + off[2]])
        })
        .filter(|&p| !spheres.iter().any(|s| s.contains(p)))
        .count()
}

/// The cover's volume outside the segment over the segment's volume, and the largest distance
/// from a voxel centre inside the cover to the segment's nearest voxel centre.
fn tightness(map: &LabelMap, label: i64, voxels: &[[i64; 3]], spheres: &[Sphere]) -> (f64, f64) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for s in spheres {
        for n in 0..8 {
            let corner =
                [0, 1, 2].map(|k| s.center[k] + if n >> k & 1 == 1 { s.radius } else { -s.radius });
            let g = map.grid(corner);
            for k in 0..3 {
                lo[k] = lo[k].min(g[k].floor());
                hi[k] = hi[k].max(g[k].ceil());
            }
        }
    }
    let boundary: Vec<[f64; 3]> = voxels
        .iter()
        .filter(|v| {
            [[1, 0, 0], [0, 1, 0], [0, 0, 1]].iter().any(|d| {
                map.at(v[0] + d[0], v[1] + d[1], v[2] + d[2]) != label
                    || map.at(v[0] - d[0], v[1] - d[1], v[2] - d[2]) != label
            })
        })
        .map(|v| centre_of(map, v))
        .collect();
    let (mut outside, mut farthest) = (0usize, 0.0f64);
    let inside = |p: [f64; 3]| spheres.iter().any(|s| s.contains(p));
    let (lo, hi) = (lo.map(|x| x as i64), hi.map(|x| x as i64));
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            for i in lo[0]..=hi[0] {
                if map.at(i, j, k) == label {
                    continue;
                }
                // Eight samples a quarter voxel from the centre, an eighth of the voxel each.
                let g = [i, j, k].map(|x| x as f64);
                outside += (0..8)
                    .filter(|n| {
                        let d = [0, 1, 2].map(|a| if n >> a & 1 == 1 { 0.25 } else { -0.25 });
                        inside(map.world([g[0] + d[0], g[1] + d[1], g[2] + d[2]]))
                    })
                    .count();
                let p = map.world(g);
                if inside(p) {
                    let near = boundary
                        .iter()
                        .map(|&q| dist(p, q))
                        .fold(f64::INFINITY, f64::min);
                    farthest = farthest.max(near);
                }
            }
        }
    }
    (outside as f64 / 8.0 / voxels.len() as f64, farthest)
}
