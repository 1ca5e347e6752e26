//! A segment's deepest point: the voxel centre farthest from anything outside the segment, where
//! a needle aimed at the segment should end (`[target] label = N`).
//!
//! Distances come from an exact Euclidean distance transform on the voxel grid (Felzenszwalb and
//! Huttenlocher, "Distance transforms of sampled functions", Theory of Computing 2012: one pass
//! per axis of the lower envelope of parabolas), with each axis's own spacing: exact for grids
//! whose axes are orthogonal, as scanners' are.

use super::edt::squared_edt;
use super::label_map::LabelMap;
use anyhow::{bail, Result};

/// The world point (RAS mm) of the voxel of `label` farthest from the segment's outside, and
/// that distance (mm). Ties go to the first voxel in the file's order.
pub fn deepest_point(map: &LabelMap, label: i64) -> Result<([f64; 3], f64)> {
    let voxels = map.voxels_of(label);
    if voxels.is_empty() {
        bail!("label {label} has no voxels");
    }
    // The segment's box, one voxel of outside around it.
    let lo = [0, 1, 2].map(|k| voxels.iter().map(|v| v[k]).min().unwrap_or(0) - 1);
    let hi = [0, 1, 2].map(|k| voxels.iter().map(|v| v[k]).max().unwrap_or(0) + 1);
    let n = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as usize);
    let index = |i: usize, j: usize, k: usize| i + n[0] * (j + n[1] * k);
    let mut inside = vec![false; n[0] * n[1] * n[2]];
    for v in &voxels {
        let g = [0, 1, 2].map(|a| (v[a] - lo[a]) as usize);
        inside[index(g[0], g[1], g[2])] = true;
    }
    let d = squared_edt(n, map.spacing(), |c| !inside[c]);
    let mut best = (0usize, -1.0f64);
    for (n_voxel, v) in voxels.iter().enumerate() {
        let g = [0, 1, 2].map(|a| (v[a] - lo[a]) as usize);
        let depth = d[index(g[0], g[1], g[2])];
        if depth > best.1 {
            best = (n_voxel, depth);
        }
    }
    let v = voxels[best.0];
    Ok((map.world(v.map(|x| x as f64)), best.1.sqrt()))
}
