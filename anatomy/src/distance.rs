//! How far points lie from a label map's segments themselves, not from their covers: an exact
//! Euclidean distance transform of the segments' voxels (`edt.rs`) on the map's grid, grown to
//! hold the points measured, trilinearly interpolated. The distance is to the nearest voxel
//! centre of the segments (mm); between grid points the interpolation errs by at most half a
//! voxel's diagonal. Exact on grids whose axes are orthogonal, as scanners' are.

use super::edt::{squared_edt, FAR};
use super::label_map::LabelMap;
use anyhow::{bail, Result};

/// The most cells a field may take (a path far outside a fine map would grow it past memory).
const MOST_CELLS: usize = 64 << 20;

/// The distance to some segments of one map, on a box of its grid.
pub struct Field<'a> {
    map: &'a LabelMap,
    lo: [i64; 3],
    n: [usize; 3],
    distance: Vec<f64>,
}

impl<'a> Field<'a> {
    /// The distance field of the voxels labelled `labels` in `map`, on the map's grid grown to
    /// hold `points` (RAS, mm) a cell inside.
    pub fn new(map: &'a LabelMap, labels: &[i64], points: &[[f64; 3]]) -> Result<Field<'a>> {
        let (mut lo, mut hi) = ([0i64; 3], map.dims.map(|d| d as i64 - 1));
        for p in points {
            let g = map.grid(*p);
            for k in 0..3 {
                lo[k] = lo[k].min(g[k].floor() as i64 - 1);
                hi[k] = hi[k].max(g[k].ceil() as i64 + 1);
            }
        }
        let n = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as usize);
        if n.iter().product::<usize>() > MOST_CELLS {
            bail!(
                "the path reaches too far outside the label map to measure its clearance on the \
                 map's grid ({} x {} x {} voxels)",
                n[0],
                n[1],
                n[2]
            );
        }
        let a = &map.ijk_to_ras;
        let spacing =
            [0, 1, 2].map(|c| (a[0][c] * a[0][c] + a[1][c] * a[1][c] + a[2][c] * a[2][c]).sqrt());
        let [ni, nj, nk] = map.dims.map(|d| d as i64);
        let seed = |c: usize| {
            let g = [c % n[0], c / n[0] % n[1], c / (n[0] * n[1])];
            let v = [0, 1, 2].map(|k| g[k] as i64 + lo[k]);
            let inside = v[0] >= 0 && v[1] >= 0 && v[2] >= 0 && v[0] < ni && v[1] < nj && v[2] < nk;
            inside && labels.contains(&map.labels[(v[0] + ni * (v[1] + nj * v[2])) as usize])
        };
        let distance = squared_edt(n, spacing, seed)
            .into_iter()
            .map(|d| if d >= FAR { f64::INFINITY } else { d.sqrt() })
            .collect();
        Ok(Field {
            map,
            lo,
            n,
            distance,
        })
    }

    /// The interpolated distance (mm) at `p`, which must lie in the box the field was made for.
    pub fn at(&self, p: [f64; 3]) -> f64 {
        let g = self.map.grid(p);
        let cell = [0, 1, 2].map(|k| {
            let x = g[k] - self.lo[k] as f64;
            let i = (x.floor().max(0.0) as usize).min(self.n[k].saturating_sub(2));
            (i, (x - i as f64).clamp(0.0, 1.0))
        });
        let mut sum = 0.0;
        for corner in 0..8 {
            let mut w = 1.0;
            let mut at = [0usize; 3];
            for k in 0..3 {
                let (i, t) = cell[k];
                let up = corner >> k & 1 == 1;
                at[k] = (i + usize::from(up)).min(self.n[k] - 1);
                w *= if up { t } else { 1.0 - t };
            }
            if w > 0.0 {
                sum += w * self.distance[at[0] + self.n[0] * (at[1] + self.n[1] * at[2])];
            }
        }
        sum
    }
}

/// The least distance (mm) from `points` to the voxels labelled `labels` in `map`.
pub fn least_distance(map: &LabelMap, labels: &[i64], points: &[[f64; 3]]) -> Result<f64> {
    let field = Field::new(map, labels, points)?;
    Ok(points
        .iter()
        .map(|p| field.at(*p))
        .fold(f64::INFINITY, f64::min))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the nearest voxel centre found one by one, on an anisotropic map and at points
    /// inside and outside it: within half a voxel's diagonal, exact at the grid's points.
    #[test]
    fn the_field_agrees_with_the_nearest_voxel_centre() {
        let dims = [12, 10, 6];
        let spacing = [0.7, 0.9, 2.5];
        let origin = [-3.0, 5.0, 1.0];
        let mut labels = Vec::new();
        for k in 0..6i64 {
            for j in 0..10i64 {
                for i in 0..12i64 {
                    let blob = (i - 4).pow(2) + (j - 5).pow(2) + 4 * (k - 2).pow(2) <= 6;
                    labels.push(if blob {
                        3
                    } else {
                        i64::from(i == 11 && j == 0) * 7
                    });
                }
            }
        }
        let map = LabelMap {
            dims,
            labels,
            ijk_to_ras: [0, 1, 2].map(|r| {
                let mut row = [0.0; 4];
                row[r] = spacing[r];
                row[3] = origin[r];
                row
            }),
            named: Vec::new(),
        };
        let centres: Vec<[f64; 3]> = map
            .voxels_of(3)
            .iter()
            .map(|v| map.world(v.map(|x| x as f64)))
            .collect();
        let exact = |p: [f64; 3]| {
            centres
                .iter()
                .map(|c| (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>().sqrt())
                .fold(f64::INFINITY, f64::min)
        };
        let half_diagonal = 0.5 * spacing.iter().map(|s| s * s).sum::<f64>().sqrt();
        let points: Vec<[f64; 3]> = (0..400)
            .map(|n| {
                let t = n as f64;
                [
                    -8.0 + (t * 0.37) % 20.0,
                    2.0 + (t * 0.53) % 14.0,
                    -4.0 + (t * 0.71) % 24.0,
                ]
            })
            .collect();
        let field = Field::new(&map, &[3], &points).unwrap();
        for p in &points {
            let (got, want) = (field.at(*p), exact(*p));
            assert!(
                (got - want).abs() <= half_diagonal,
                "{p:?}: {got} against {want}"
            );
        }
        for v in [[0, 0, 0], [4, 5, 2], [11, 9, 5]] {
            let p = map.world(v.map(|x: i64| x as f64));
            assert!((field.at(p) - exact(p)).abs() < 1e-9, "{v:?}");
        }
        let least = least_distance(&map, &[3], &points).unwrap();
        let want = points
            .iter()
            .map(|p| exact(*p))
            .fold(f64::INFINITY, f64::min);
        assert!((least - want).abs() <= half_diagonal);
    }
}
