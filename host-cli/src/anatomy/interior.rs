//! A segment's deepest point: the voxel centre farthest from anything outside the segment, where
//! a needle aimed at the segment should end (`[target] label = N`).
//!
//! Distances come from an exact Euclidean distance transform on the voxel grid (Felzenszwalb and
//! Huttenlocher, "Distance transforms of sampled functions", Theory of Computing 2012: one pass
//! per axis of the lower envelope of parabolas), with each axis's own spacing: exact for grids
//! whose axes are orthogonal, as scanners' are.

use super::label_map::LabelMap;
use anyhow::{bail, Result};

/// Stands for "infinitely far" in the squared distances (finite, so differences stay numbers).
const FAR: f64 = 1e20;

/// The squared distances, along one line of samples `spacing` apart, to the nearest sample of
/// `f` (squared distances already), written into `out`.
fn transform_line(f: &[f64], spacing: f64, out: &mut [f64]) {
    let n = f.len();
    let mut v = vec![0usize; n];
    let mut z = vec![0f64; n + 1];
    let mut k = 0usize;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    let x = |q: usize| q as f64 * spacing;
    for q in 1..n {
        loop {
            let p = v[k];
            let s = ((f[q] + x(q) * x(q)) - (f[p] + x(p) * x(p))) / (2.0 * (x(q) - x(p)));
            // z[0] is minus infinity: k never falls below 0.
            if s <= z[k] {
                k -= 1;
                continue;
            }
            k += 1;
            v[k] = q;
            z[k] = s;
            z[k + 1] = f64::INFINITY;
            break;
        }
    }
    let mut k = 0usize;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < x(q) {
            k += 1;
        }
        let d = x(q) - x(v[k]);
        *o = d * d + f[v[k]];
    }
}

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
    let mut d = vec![0f64; n[0] * n[1] * n[2]];
    for v in &voxels {
        let g = [0, 1, 2].map(|a| (v[a] - lo[a]) as usize);
        d[index(g[0], g[1], g[2])] = FAR;
    }
    let spacing = map.spacing();
    for axis in 0..3 {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut line = vec![0f64; n[axis]];
        let mut out = vec![0f64; n[axis]];
        for p in 0..n[a] {
            for q in 0..n[b] {
                let at = |t: usize| {
                    let mut g = [0usize; 3];
                    g[axis] = t;
                    g[a] = p;
                    g[b] = q;
                    index(g[0], g[1], g[2])
                };
                for (t, l) in line.iter_mut().enumerate() {
                    *l = d[at(t)];
                }
                transform_line(&line, spacing[axis], &mut out);
                for (t, o) in out.iter().enumerate() {
                    d[at(t)] = *o;
                }
            }
        }
    }
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
