//! A greedy cover of a segment by balls on its medial axis.
//!
//! The exact Euclidean distance transform gives each cell of the segment its depth `D`: the
//! distance from its centre to the nearest centre outside the segment. A ball about a cell `c`
//! of radius `D(c) + k` reaches at most about `k` beyond the segment, since the segment holds
//! the ball of radius `D(c)` about `c` up to a voxel's rounding. The cover takes the deepest cell
//! that no ball holds yet, climbs from it to deeper cells (towards the medial axis) for as long as
//! the ball there still holds the cell whole, and places the ball there: a few large balls along
//! the medial axis fill an organ, and the overshoot `k` bounds how far any reaches out of it.
//! A cell counts as held when all eight of its corners lie inside one ball.

use super::block::Block;
use super::edt::squared_edt;

/// A ball of the cover on the box's grid: its centre cell and its radius (mm, no margin).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    /// The centre cell (box coordinates).
    pub cell: [usize; 3],
    /// The radius (mm).
    pub radius: f64,
}

/// The depths of a segment's cells: their squared distance (mm²) to the nearest centre outside
/// the segment (0 outside).
pub fn depths(b: &Block) -> Vec<f64> {
    squared_edt(b.n, b.spacing, |c| !b.inside[c])
}

/// The cells of the segment, deepest first (ties in box order).
pub fn deepest_first(b: &Block, depth: &[f64]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..b.inside.len()).filter(|&c| b.inside[c]).collect();
    order.sort_by(|&x, &y| depth[y].total_cmp(&depth[x]).then(x.cmp(&y)));
    order
}

/// What a cover must fit around besides the segment: balls (centre cell in box coordinates,
/// radius in mm without the margin) where no path goes may be coarse, and no ball may hold a
/// point kept out (the entry, the target).
pub struct Fit<'a> {
    /// Whether the ball lies wholly where no path goes.
    pub beyond_reach: &'a dyn Fn([usize; 3], f64) -> bool,
    /// The overshoot (mm) of balls beyond reach.
    pub coarse_k: f64,
    /// Whether the ball holds a point kept out.
    pub holds_kept_out: &'a dyn Fn([usize; 3], f64) -> bool,
}

/// The medial balls with overshoot `k` (mm) that hold every cell of the segment, fitted to
/// `fit` when given; `None` when that takes more than `most` balls.
pub fn medial_cover(
    b: &Block,
    depth: &[f64],
    order: &[usize],
    k: f64,
    most: usize,
    fit: Option<&Fit<'_>>,
) -> Option<Vec<Ball>> {
    let mut held = vec![false; b.inside.len()];
    let mut balls = Vec::new();
    for &u in order {
        if held[u] {
            continue;
        }
        if balls.len() == most {
            return None;
        }
        let uc = b.cell(u);
        let ball = match fit {
            None => place(b, depth, uc, k),
            Some(f) => fitted(b, depth, uc, k, f),
        };
        hold(b, &mut held, ball.cell, ball.radius);
        balls.push(ball);
    }
    Some(pruned(b, balls))
}

/// The ball that holds cell `u`: coarse where no path goes; else with overshoot `k`, less as
/// far as it takes to keep the points kept out outside it, down to the ball about `u` alone.
fn fitted(b: &Block, depth: &[f64], u: [usize; 3], k: f64, f: &Fit<'_>) -> Ball {
    if f.coarse_k > k {
        let coarse = place(b, depth, u, f.coarse_k);
        if (f.beyond_reach)(coarse.cell, coarse.radius) {
            return coarse;
        }
    }
    let clear = |ball: &Ball| !(f.holds_kept_out)(ball.cell, ball.radius);
    [1.0, 0.5, 0.25, 0.0]
        .iter()
        .map(|s| place(b, depth, u, s * k))
        .find(clear)
        .unwrap_or(Ball {
            cell: u,
            radius: b.farthest_corner(u, u),
        })
}

/// The ball with overshoot `k` that holds cell `u`, on the medial axis above it.
fn place(b: &Block, depth: &[f64], u: [usize; 3], k: f64) -> Ball {
    let c = climb(b, depth, u, k);
    let radius = (depth[b.index(c)].sqrt() + k).max(b.farthest_corner(c, u));
    Ball { cell: c, radius }
}

/// The cells of the segment that the ball holds whole (box indices).
fn held_by(b: &Block, ball: &Ball) -> Vec<usize> {
    let (lo, hi) = b.window(ball.cell, b.reach(ball.radius));
    let mut out = Vec::new();
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let v = b.index([x, y, z]);
                if b.inside[v] && b.farthest_corner(ball.cell, [x, y, z]) <= ball.radius {
                    out.push(v);
                }
            }
        }
    }
    out
}

/// `balls` without those whose cells others hold too (the last placed, the smallest, dropped
/// first), each then shrunk to the farthest corner of the cells it alone is given (each cell to
/// the first ball that holds it).
fn pruned(b: &Block, mut balls: Vec<Ball>) -> Vec<Ball> {
    let held: Vec<Vec<usize>> = balls.iter().map(|ball| held_by(b, ball)).collect();
    let mut count = vec![0u16; b.inside.len()];
    for cells in &held {
        for &v in cells {
            count[v] = count[v].saturating_add(1);
        }
    }
    let mut keep = vec![true; balls.len()];
    for n in (0..balls.len()).rev() {
        if held[n].iter().all(|&v| count[v] >= 2) {
            keep[n] = false;
            for &v in &held[n] {
                count[v] -= 1;
            }
        }
    }
    let mut owner = vec![usize::MAX; b.inside.len()];
    let mut radius = vec![0.0f64; balls.len()];
    for (n, cells) in held.iter().enumerate().filter(|(n, _)| keep[*n]) {
        for &v in cells {
            if owner[v] == usize::MAX {
                owner[v] = n;
                radius[n] = radius[n].max(b.farthest_corner(balls[n].cell, b.cell(v)));
            }
        }
    }
    for (n, ball) in balls.iter_mut().enumerate() {
        ball.radius = radius[n];
    }
    balls
        .into_iter()
        .zip(keep)
        .filter(|(ball, k)| *k && ball.radius > 0.0)
        .map(|(ball, _)| ball)
        .collect()
}

/// From cell `u`, the deepest neighbour whose ball still holds `u`, step by step.
fn climb(b: &Block, depth: &[f64], u: [usize; 3], k: f64) -> [usize; 3] {
    let mut c = u;
    loop {
        let (lo, hi) = b.window(c, [1, 1, 1]);
        let mut best: Option<([usize; 3], f64)> = None;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let w = [x, y, z];
                    let dw = depth[b.index(w)];
                    let deeper = dw > best.map_or(depth[b.index(c)], |(_, d)| d);
                    if deeper && b.inside[b.index(w)] && b.farthest_corner(w, u) <= dw.sqrt() + k {
                        best = Some((w, dw));
                    }
                }
            }
        }
        match best {
            Some((w, _)) => c = w,
            None => return c,
        }
    }
}

/// Marks the segment's cells the ball about `c` of `radius` holds whole.
fn hold(b: &Block, held: &mut [bool], c: [usize; 3], radius: f64) {
    let (lo, hi) = b.window(c, b.reach(radius));
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let v = b.index([x, y, z]);
                if b.inside[v] && !held[v] && b.farthest_corner(c, [x, y, z]) <= radius {
                    held[v] = true;
                }
            }
        }
    }
}
