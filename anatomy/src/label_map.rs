//! A 3-D label map: integer labels on a voxel grid, the grid's place in the world (RAS, mm),
//! and the names of its segments where the file gives them.

use anyhow::{bail, Result};

/// One labelled structure of a map.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// Its name (Slicer's segment name, or `label N`).
    pub name: String,
    /// The voxel value that marks it.
    pub label: i64,
}

/// A label map in the world frame: RAS, millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelMap {
    /// Voxels along i, j and k.
    pub dims: [usize; 3],
    /// One label per voxel, i fastest, then j, then k.
    pub labels: Vec<i64>,
    /// World position (RAS, mm) of voxel (i, j, k)'s centre: `ijk_to_ras · [i, j, k, 1]`.
    pub ijk_to_ras: [[f64; 4]; 3],
    /// The segments the file names (empty when it names none).
    pub named: Vec<Segment>,
}

impl LabelMap {
    /// `self` if its grid, labels and affine are usable.
    pub fn validated(self) -> Result<LabelMap> {
        let n: usize = self.dims.iter().product();
        if n == 0 {
            bail!("the map has no voxels (sizes {:?})", self.dims);
        }
        if n != self.labels.len() {
            bail!(
                "the map's sizes {:?} give {n} voxels but it holds {}",
                self.dims,
                self.labels.len()
            );
        }
        let a = &self.ijk_to_ras;
        if a.iter().flatten().any(|v| !v.is_finite()) {
            bail!("the voxel-to-world transform is not finite");
        }
        let det = det3(self.linear());
        let scale = self.spacing().iter().product::<f64>();
        if det.abs().partial_cmp(&(1e-9 * scale.max(1e-30))) != Some(std::cmp::Ordering::Greater)
            || scale == 0.0
        {
            bail!("the voxel-to-world transform is singular (its axes do not span 3-D)");
        }
        Ok(self)
    }

    /// The label of voxel (i, j, k); 0 outside the grid.
    pub fn at(&self, i: i64, j: i64, k: i64) -> i64 {
        let [ni, nj, nk] = self.dims.map(|d| d as i64);
        if i < 0 || j < 0 || k < 0 || i >= ni || j >= nj || k >= nk {
            return 0;
        }
        self.labels[(i + ni * (j + nj * k)) as usize]
    }

    /// The world point (RAS, mm) of grid coordinates `p` (voxel centres at whole numbers).
    pub fn world(&self, p: [f64; 3]) -> [f64; 3] {
        let a = &self.ijk_to_ras;
        [0, 1, 2].map(|r| a[r][0] * p[0] + a[r][1] * p[1] + a[r][2] * p[2] + a[r][3])
    }

    /// The length of a step along i, j and k (mm).
    pub fn spacing(&self) -> [f64; 3] {
        let a = &self.ijk_to_ras;
        [0, 1, 2].map(|c| (a[0][c] * a[0][c] + a[1][c] * a[1][c] + a[2][c] * a[2][c]).sqrt())
    }

    /// The volume of one voxel (mm³).
    pub fn voxel_volume(&self) -> f64 {
        det3(self.linear()).abs()
    }

    /// The affine's linear part (the grid's axes as columns).
    fn linear(&self) -> [[f64; 3]; 3] {
        let a = &self.ijk_to_ras;
        [0, 1, 2].map(|r| [a[r][0], a[r][1], a[r][2]])
    }

    /// The grid coordinates of the world point `p`: [`LabelMap::world`] inverted (Cramer's
    /// rule; the affine is not singular, as [`LabelMap::validated`] checks).
    pub fn grid(&self, p: [f64; 3]) -> [f64; 3] {
        let m = self.linear();
        let a = &self.ijk_to_ras;
        let d = [0, 1, 2].map(|r| p[r] - a[r][3]);
        let det = det3(m);
        std::array::from_fn(|k| {
            let mut n = m;
            for (row, dr) in n.iter_mut().zip(d) {
                row[k] = dr;
            }
            det3(n) / det
        })
    }

    /// The segments present: the named ones with at least one voxel, in the file's order, then a
    /// `label N` for every other label but 0 that voxels hold, in label order (a `.seg.nrrd`
    /// whose voxels carry values its header does not name keeps them: nothing is dropped).
    pub fn segments(&self) -> Vec<Segment> {
        let mut present: Vec<i64> = self.labels.iter().copied().filter(|&l| l != 0).collect();
        present.sort_unstable();
        present.dedup();
        let named = |l: i64| self.named.iter().any(|s| s.label == l);
        self.named
            .iter()
            .filter(|s| present.binary_search(&s.label).is_ok())
            .cloned()
            .chain(
                present
                    .iter()
                    .copied()
                    .filter(|&l| !named(l))
                    .map(|label| Segment {
                        name: format!("label {label}"),
                        label,
                    }),
            )
            .collect()
    }

    /// The grid coordinates of every voxel labelled `label`.
    pub fn voxels_of(&self, label: i64) -> Vec<[i64; 3]> {
        let [ni, nj, _] = self.dims;
        self.labels
            .iter()
            .enumerate()
            .filter(|(_, &l)| l == label)
            .map(|(n, _)| {
                let (i, rest) = (n % ni, n / ni);
                [i as i64, (rest % nj) as i64, (rest / nj) as i64]
            })
            .collect()
    }
}

/// The determinant of a 3×3 matrix (rows).
fn det3(m: [[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// A stored value as a label: only whole numbers are labels.
pub(super) fn whole_label(v: f64) -> Result<i64> {
    if v.is_finite() && v.fract() == 0.0 && v.abs() < 9.0e15 {
        Ok(v as i64)
    } else {
        bail!("the value {v} is not a whole-number label")
    }
}
