//! The box of voxels around one segment that its cover is built and measured on: the segment's
//! bounding box grown by a border, the segment's cells marked, and the map's geometry rounded so
//! that the same anatomy stored with a float32 affine (NIfTI) or a float64 one (NRRD) takes the
//! same decisions.

use super::label_map::LabelMap;

/// A box of cells around a segment.
pub struct Block {
    /// The grid coordinates of the box's first cell.
    pub lo: [i64; 3],
    /// Cells along i, j and k.
    pub n: [usize; 3],
    /// Whether each cell (i fastest) belongs to the segment.
    pub inside: Vec<bool>,
    /// The affine's linear part (grid axes as columns), rounded to 1e-6 mm.
    pub axes: [[f64; 3]; 3],
    /// The length of a step along each axis (mm), from `axes`.
    pub spacing: [f64; 3],
    /// The world offsets of a cell's eight corners from its centre (from `axes`).
    pub corners: [[f64; 3]; 8],
}

fn rounded(x: f64) -> f64 {
    (x * 1e6).round() / 1e6
}

impl Block {
    /// The box around `voxels` (grid coordinates, not empty) of `map`, grown by `border` cells
    /// on every side.
    pub fn around(map: &LabelMap, voxels: &[[i64; 3]], border: [i64; 3]) -> Block {
        let lo = [0, 1, 2].map(|k| voxels.iter().map(|v| v[k]).min().unwrap_or(0) - border[k]);
        let hi = [0, 1, 2].map(|k| voxels.iter().map(|v| v[k]).max().unwrap_or(0) + border[k]);
        let n = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as usize);
        let mut inside = vec![false; n[0] * n[1] * n[2]];
        for v in voxels {
            let g = [0, 1, 2].map(|k| (v[k] - lo[k]) as usize);
            inside[g[0] + n[0] * (g[1] + n[1] * g[2])] = true;
        }
        let a = &map.ijk_to_ras;
        let axes = [0, 1, 2].map(|r| [0, 1, 2].map(|c| rounded(a[r][c])));
        let spacing = [0, 1, 2].map(|c| {
            (axes[0][c] * axes[0][c] + axes[1][c] * axes[1][c] + axes[2][c] * axes[2][c]).sqrt()
        });
        let corners = std::array::from_fn(|m| {
            let d = [0, 1, 2].map(|k| if m >> k & 1 == 1 { 0.5 } else { -0.5 });
            [0, 1, 2].map(|r| axes[r][0] * d[0] + axes[r][1] * d[1] + axes[r][2] * d[2])
        });
        Block {
            lo,
            n,
            inside,
            axes,
            spacing,
            corners,
        }
    }

    /// The index of cell `g` (box coordinates).
    pub fn index(&self, g: [usize; 3]) -> usize {
        g[0] + self.n[0] * (g[1] + self.n[1] * g[2])
    }

    /// The box coordinates of cell `c`.
    pub fn cell(&self, c: usize) -> [usize; 3] {
        [
            c % self.n[0],
            c / self.n[0] % self.n[1],
            c / (self.n[0] * self.n[1]),
        ]
    }

    /// The world offset (mm, rounded axes) of a step of `d` cells.
    pub fn offset(&self, d: [f64; 3]) -> [f64; 3] {
        let a = &self.axes;
        [0, 1, 2].map(|r| a[r][0] * d[0] + a[r][1] * d[1] + a[r][2] * d[2])
    }

    /// The distance (mm) from the centre of cell `c` to the farthest corner of cell `v`.
    pub fn farthest_corner(&self, c: [usize; 3], v: [usize; 3]) -> f64 {
        let d = self.offset([0, 1, 2].map(|k| v[k] as f64 - c[k] as f64));
        self.corners
            .iter()
            .map(|o| (d[0] + o[0]).powi(2) + (d[1] + o[1]).powi(2) + (d[2] + o[2]).powi(2))
            .fold(0.0, f64::max)
            .sqrt()
    }

    /// Half a cell's longest diagonal (mm).
    pub fn half_diagonal(&self) -> f64 {
        self.corners
            .iter()
            .map(|o| (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt())
            .fold(0.0, f64::max)
    }

    /// The cells of the box within `reach` cells of `c` along each axis, clipped to the box:
    /// the lowest and highest box coordinates.
    pub fn window(&self, c: [usize; 3], reach: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        (
            [0, 1, 2].map(|k| c[k].saturating_sub(reach[k])),
            [0, 1, 2].map(|k| (c[k] + reach[k]).min(self.n[k] - 1)),
        )
    }

    /// How many cells along each axis a ball of `radius` mm reaches (a cell's step along an
    /// axis is at least its spacing's projection; for sheared grids the smallest singular
    /// value bounds it, taken here as the spacing times the axes' orthogonality).
    pub fn reach(&self, radius: f64) -> [usize; 3] {
        let s = self.min_step();
        [0, 1, 2].map(|k| (radius / s[k]).ceil() as usize + 1)
    }

    /// Per axis, the smallest world distance a step along that axis can contribute once the
    /// other axes are free: the cell's spacing scaled by the sine of its angle to the plane of
    /// the other two (the spacing itself on orthogonal grids).
    fn min_step(&self) -> [f64; 3] {
        let a = &self.axes;
        let col = |c: usize| [a[0][c], a[1][c], a[2][c]];
        [0, 1, 2].map(|k| {
            let (u, w) = (col((k + 1) % 3), col((k + 2) % 3));
            let normal = [
                u[1] * w[2] - u[2] * w[1],
                u[2] * w[0] - u[0] * w[2],
                u[0] * w[1] - u[1] * w[0],
            ];
            let len = (normal[0].powi(2) + normal[1].powi(2) + normal[2].powi(2)).sqrt();
            let v = col(k);
            (v[0] * normal[0] + v[1] * normal[1] + v[2] * normal[2]).abs() / len.max(1e-300)
        })
    }
}
