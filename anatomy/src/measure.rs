//! How tight a cover is, sampled at eight points a quarter voxel from each voxel centre (an
//! eighth of the voxel each): the cover's volume outside the segment, outside the segment dilated
//! by the margin, and the farthest a voxel centre inside the cover lies from the segment.

use super::block::Block;
use super::edt::squared_edt;

/// The eight sample offsets (in cells) about a cell centre.
fn samples() -> [[f64; 3]; 8] {
    std::array::from_fn(|m| [0, 1, 2].map(|k| if m >> k & 1 == 1 { 0.25 } else { -0.25 }))
}

/// The segment's cells and their neighbourhood as the measure needs them, built once a segment.
pub struct Dilated {
    /// Per cell, which of its eight samples lie within the margin of a segment voxel's cube.
    pub bits: Vec<u8>,
    /// Per cell, the distance (mm) from its centre to the nearest segment voxel centre.
    pub to_segment: Vec<f64>,
}

/// The distance (mm) from the point `p` (box coordinates) to the cube of cell `v`.
fn to_cube(b: &Block, p: [f64; 3], v: [usize; 3]) -> f64 {
    // The nearest point of the cube, in cell coordinates, clamps p to the cube (exact for
    // orthogonal grids; on sheared ones an over-estimate, which only counts less as dilated).
    let q = [0, 1, 2].map(|k| p[k].clamp(v[k] as f64 - 0.5, v[k] as f64 + 0.5));
    let d = b.offset([0, 1, 2].map(|k| p[k] - q[k]));
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Which samples of every cell lie in the segment dilated by `margin` (mm).
pub fn dilated(b: &Block, margin: f64) -> Dilated {
    let to_segment: Vec<f64> = squared_edt(b.n, b.spacing, |c| b.inside[c])
        .into_iter()
        .map(f64::sqrt)
        .collect();
    let hd = b.half_diagonal();
    let reach = b.reach(margin + hd);
    let offsets = samples();
    // A sample lies within a quarter cell of its centre (half the half diagonal), and a cube's
    // points within `hd` of its centre: a voxel whose centre is farther than this from the
    // cell's holds no point within the margin of any of its samples.
    let limit = margin + 1.5 * hd + 1e-6;
    let mut near: Vec<(f64, [usize; 3])> = Vec::new();
    let mut bits = Vec::with_capacity(b.inside.len());
    for (c, &d) in to_segment.iter().enumerate() {
        if b.inside[c] || d + 0.5 * hd <= margin {
            bits.push(0xff);
            continue;
        }
        if d - 1.5 * hd > margin || margin == 0.0 {
            bits.push(0);
            continue;
        }
        let g = b.cell(c);
        let (lo, hi) = b.window(g, reach);
        near.clear();
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let w = [x, y, z];
                    if b.inside[b.index(w)] {
                        let o = b.offset([0, 1, 2].map(|k| w[k] as f64 - g[k] as f64));
                        let apart = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt();
                        if apart <= limit {
                            near.push((apart, w));
                        }
                    }
                }
            }
        }
        // Nearest first: a sample within the margin is found after a voxel or two.
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut cell_bits = 0u8;
        for (m, o) in offsets.iter().enumerate() {
            let p = [0, 1, 2].map(|k| g[k] as f64 + o[k]);
            let within = near.iter().any(|&(_, w)| to_cube(b, p, w) <= margin);
            cell_bits |= u8::from(within) << m;
        }
        bits.push(cell_bits);
    }
    Dilated { bits, to_segment }
}

/// A cover's tightness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tightness {
    /// Its volume outside the segment over the segment's volume.
    pub outside: f64,
    /// Its volume outside the dilated segment over the dilated segment's volume.
    pub outside_dilated: f64,
    /// The part of `outside_dilated` a needle can reach (all of it when no reach is given).
    pub outside_in_reach: f64,
    /// The dilated segment's volume over the segment's (1 without a margin).
    pub dilated_over_segment: f64,
    /// The largest distance (mm) from a voxel centre inside the cover to the segment's nearest
    /// voxel centre.
    pub farthest: f64,
}

/// The tightness of the balls `(centre in cells, radius mm)` about the segment of `b`, whose
/// dilation is `d`; `in_reach` tells the cells a needle can reach (every cell when `None`).
/// The balls must lie inside the box.
pub fn tightness(
    b: &Block,
    d: &Dilated,
    balls: &[([f64; 3], f64)],
    in_reach: Option<&dyn Fn(usize) -> bool>,
) -> Tightness {
    let offsets = samples();
    // Bits 0-7: the samples inside some ball; bit 8: the centre.
    let mut cover = vec![0u16; b.inside.len()];
    for &(c, r) in balls {
        let g = c.map(|x| x.round().max(0.0) as usize);
        let (lo, hi) = b.window(g, b.reach(r));
        let within = |p: [f64; 3]| {
            let o = b.offset([0, 1, 2].map(|k| p[k] - c[k]));
            o[0] * o[0] + o[1] * o[1] + o[2] * o[2] <= r * r
        };
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let at = b.index([x, y, z]);
                    if cover[at] == 0x1ff {
                        continue;
                    }
                    let p = [x, y, z].map(|v| v as f64);
                    let mut bits = u16::from(within(p)) << 8;
                    for (m, o) in offsets.iter().enumerate() {
                        bits |= u16::from(within([p[0] + o[0], p[1] + o[1], p[2] + o[2]])) << m;
                    }
                    cover[at] |= bits;
                }
            }
        }
    }
    let (mut out, mut out_dilated, mut dilated, mut voxels) = (0u64, 0u64, 0u64, 0u64);
    let mut out_reach = 0u64;
    let mut farthest = 0.0f64;
    for (c, &bits) in cover.iter().enumerate() {
        let samples = (bits & 0xff) as u8;
        dilated += u64::from(d.bits[c].count_ones());
        if b.inside[c] {
            voxels += 1;
            continue;
        }
        out += u64::from(samples.count_ones());
        let beyond = u64::from((samples & !d.bits[c]).count_ones());
        out_dilated += beyond;
        if beyond > 0 && in_reach.is_none_or(|r| r(c)) {
            out_reach += beyond;
        }
        if bits & 0x100 != 0 {
            farthest = farthest.max(d.to_segment[c]);
        }
    }
    let v8 = 8.0 * voxels.max(1) as f64;
    Tightness {
        outside: out as f64 / v8,
        outside_dilated: out_dilated as f64 / dilated.max(1) as f64,
        outside_in_reach: out_reach as f64 / dilated.max(1) as f64,
        dilated_over_segment: dilated as f64 / v8,
        farthest,
    }
}
