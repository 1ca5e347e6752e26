//! Deterministic starting points: a sweep over planar paths that end exactly on the target.
//!
//! A seed lies in a plane through the entry and the target (the y-z plane in plane mode; in 3-D,
//! one of the planes the per-form solve turns about the entry-target line). In that plane the
//! free parameters of a form (the heading, and the lengths of all but the last two segments) run
//! over a grid, and the last two segments are solved in closed form so that the path ends on
//! the target: arc then line is the tangent from the arc's circle to the target; line then arc is
//! a quadratic in the line's length; arc then opposite arc intersects two circles. Every grid point
//! therefore samples the constraint manifold itself, and the sweep sees every basin wider than
//! its spacing. Seeds are handed on as problem variables.

use crate::model::form::SegmentKind;
use crate::optim::problem::{Problem, Vars};
use crate::search::in_plane_geometry::{advance_from, complete, heading_of_bend, turn, Pose, Tail};
pub use crate::search::sweep_plane::NEAR_MISS;
use crate::search::sweep_plane::{pieces, Piece, Pieces, PlanarPath, SweepPlane};
use crate::MAX_CONTROL_DEGREE;

/// Widest heading from the chord swept (radians, about 86 degrees).
const HEADING_SPAN: f32 = 1.5;

/// Grid sizes: headings, then lengths of each free segment, by control degree.
pub fn grid(len: usize) -> (usize, usize) {
    match len {
        0..=2 => (96, 1),
        3 => (32, 12),
        _ => (14, 6),
    }
}

/// Where a sweep's seeds go.
pub trait SeedSink {
    /// The objective at or above which a seed is of no use (infinite while any seed is).
    fn bound(&self) -> f32;
    /// A seed that ends on the target within every bound and clear of every obstacle.
    fn offer(&mut self, objective: f32, x: &Vars);
    /// A seed that ends on the target within every bound but cuts into an obstacle, by less
    /// than [`NEAR_MISS`]: `min_clearance` says how much; `x` makes its variables.
    fn near_miss(&mut self, min_clearance: f32, x: &dyn Fn() -> Option<Vars>);
}

/// Offers `sink` every admissible planar seed of `p` in the plane turned by `psi`, with arc sides
/// `sides` (bit set: the arc bends left of the heading, seen along the plane normal). Returns the
/// number of seeds scored.
///
/// The form is swept whole and then once more without each of its lines: an optimum whose line
/// has length zero lies on the edge of the form's completions, where a grid rarely lands.
/// Seeds are scored in their plane (the distance from a point to a planar path is its in-plane
/// distance combined with its height over the plane), which costs a fraction of a 3-D
/// evaluation; only the seeds offered are turned into problem variables.
///
/// `planned_without` has bit i set when the form without its line i has been planned already:
/// its best path then comes in as an extension start, and that sweep is left out.
pub fn sweep(
    p: &Problem,
    psi: f32,
    sides: u8,
    planned_without: u8,
    sink: &mut dyn SeedSink,
) -> u32 {
    let plane = SweepPlane::new(p, psi, sides);
    let mut scored = sweep_pieces(p, &plane, &pieces(p, &plane.sides, 0), sink);
    if p.form.len() > 1 {
        for i in 0..p.form.len() {
            if p.form.kind(i) == SegmentKind::Line && planned_without & (1 << i) == 0 {
                let without = pieces(p, &plane.sides, 1 << i);
                scored += sweep_pieces(p, &plane, &without, sink);
            }
        }
    }
    scored
}

/// Offers `sink` the seeds of `pieces` in `plane`; returns the number of seeds scored.
fn sweep_pieces(p: &Problem, plane: &SweepPlane, pieces: &Pieces, sink: &mut dyn SeedSink) -> u32 {
    let mut sweep = PieceSweep::new(p, plane, pieces, sink);
    if pieces.len() == 1 {
        sweep.single_piece();
    } else if let Some(grid) = FreeGrid::new(p, plane, pieces) {
        sweep.grid(&grid);
    }
    sweep.scored
}

/// One sweep of a form's pieces in one plane: what all its seeds share, and where they go.
struct PieceSweep<'a, 's> {
    p: &'a Problem<'a>,
    plane: &'a SweepPlane,
    pieces: &'a Pieces,
    sink: &'s mut dyn SeedSink,
    /// The sink's bound as it stands (it changes only when a seed is offered): a probe whose free
    /// pieces plus the straight distance left to the target reach it cannot emit a seed.
    bound: f32,
    /// Each piece's longest length (mm): its segments' bound (radius-lengths) times the radius.
    longest: [f32; MAX_CONTROL_DEGREE],
    /// The part of the objective every path of the form pays: a4 N.
    fixed: f32,
    /// Seeds scored so far.
    scored: u32,
}

impl<'a, 's> PieceSweep<'a, 's> {
    fn new(
        p: &'a Problem<'a>,
        plane: &'a SweepPlane,
        pieces: &'a Pieces,
        sink: &'s mut dyn SeedSink,
    ) -> Self {
        let fixed = p.scenario.weights.control * p.form.len() as f32;
        let bound = sink.bound();
        let mut longest = [0.0f32; MAX_CONTROL_DEGREE];
        for (l, piece) in longest.iter_mut().zip(pieces.iter()) {
            *l = segment_upper(p, piece) * p.radius;
        }
        PieceSweep {
            p,
            plane,
            pieces,
            sink,
            bound,
            longest,
            fixed,
            scored: 0,
        }
    }

    /// Scores the planar path of `heading` (its (sin, cos): `sc`) and `piece_lengths` and offers
    /// it to the sink (or, if it cuts an obstacle by less than a near miss, hands it on as one).
    /// Returns its smallest clearance: negative when it touches an obstacle, minus infinity when
    /// it was not scored (a piece out of its bounds, the heading outside the tilt cone, or a
    /// length that alone reaches the bound).
    fn emit(
        &mut self,
        heading: f32,
        sc: (f32, f32),
        piece_lengths: &[f32; MAX_CONTROL_DEGREE],
    ) -> f32 {
        let (p, plane, pieces) = (self.p, self.plane, self.pieces);
        let w = &p.scenario.weights;
        let mut length = 0.0;
        for ((piece, len), longest) in pieces.iter().zip(piece_lengths).zip(&self.longest) {
            let each = len / f32::from(piece.count);
            if !(each >= 0.0 && each <= *longest) {
                return f32::NEG_INFINITY;
            }
            length += len;
        }
        // D >= 0, so a1 L + a4 N bounds F from below.
        if !plane.within_tilt(p, sc) || w.length * length + self.fixed >= self.bound {
            return f32::NEG_INFINITY;
        }
        self.scored += 1;
        let (risk, min_clearance) = plane.clearances(p, heading, sc, pieces, piece_lengths);
        let risk_term = if w.risk == 0.0 { 0.0 } else { w.risk * risk };
        let objective = w.length * length + risk_term + self.fixed;
        let variables = || planar_variables(p, plane, pieces, heading, piece_lengths);
        if min_clearance > p.min_clearance && objective.is_finite() {
            if let Some(x) = variables() {
                self.sink.offer(objective, &x);
                self.bound = self.sink.bound();
            }
        } else if min_clearance > p.min_clearance - NEAR_MISS {
            self.sink.near_miss(min_clearance, &variables);
        }
        min_clearance
    }

    /// A form of one piece has no free parameter: a line straight to the target, or an arc
    /// through it (one of the two circles of the radius through the entry and the target).
    fn single_piece(&mut self) {
        let (r, dist) = (self.p.radius, self.plane.dist);
        match self.pieces[0].kind {
            SegmentKind::Line => {
                self.emit(0.0, crate::fmath::sincos(0.0), &[dist, 0.0, 0.0, 0.0]);
            }
            SegmentKind::Arc => {
                if dist > 2.0 * r {
                    return;
                }
                let side = self.pieces[0].side;
                let off = crate::fmath::sqrt(r * r - dist * dist / 4.0);
                for cy in [off, -off] {
                    let cx = dist / 2.0;
                    let h0 = heading_of_bend((cx / r, cy / r), side);
                    let h1 = heading_of_bend(((cx - dist) / r, cy / r), side);
                    let sc = crate::fmath::sincos(h0);
                    self.emit(h0, sc, &[r * turn(h0, h1, side), 0.0, 0.0, 0.0]);
                }
            }
        }
    }

    /// Probes every point of `grid`: its headings (and the two at the tilt bound, where optima
    /// often lie, with finer lengths), then the lengths of the free pieces; a probe that just
    /// misses is refined.
    fn grid(&mut self, grid: &FreeGrid) {
        let free = grid.free;
        let combos = grid.steps.pow(free as u32);
        for hi in 0..grid.headings + 2 {
            let Some(heading) = grid.heading(self.plane, hi) else {
                continue;
            };
            let heading_sc = crate::fmath::sincos(heading);
            // Outside the tilt cone every seed is refused, and no probe of it is refined.
            if !self.plane.within_tilt(self.p, heading_sc) {
                continue;
            }
            // The bound is one line in the grid's space: it gets a finer grid of lengths.
            let (steps, combos) = if hi < grid.headings {
                (grid.steps, combos)
            } else {
                let finer = grid.steps * BOUND_FINER;
                (finer, finer.pow(free as u32))
            };
            let mut turned = None;
            for combo in 0..combos {
                let mut cell = [0.0f32; MAX_CONTROL_DEGREE];
                let mut c = combo;
                for f in cell.iter_mut().take(free) {
                    *f = ((c % steps) as f32 + 0.5) / steps as f32;
                    c /= steps;
                }
                let nearest = self.probe(grid, heading, heading_sc, &cell);
                // A probe that just misses (a thin feasible sliver between obstacles can fall
                // between grid points) is followed by a finer grid over its cell. In 3-D the SQP
                // leaves the plane and eight planes are swept: there the finer grid bought no
                // optimum in the optimality suites and cost a third of the sweep.
                if self.p.plane && nearest < 0.0 && nearest > -NEAR_MISS {
                    // The finer headings vary fastest: their (sin, cos) are taken once per heading.
                    let turned =
                        *turned.get_or_insert_with(|| refined_headings(heading, grid.heading_step));
                    self.refine(grid, &turned, &cell, steps);
                }
            }
        }
    }

    /// Probes a finer grid over the cell at `cell` (of `steps` per dimension) with the refined
    /// headings `turned`.
    // Not inlined: rarely called, and inlined it costs the grid's loop registers.
    #[inline(never)]
    fn refine(
        &mut self,
        grid: &FreeGrid,
        turned: &[(f32, (f32, f32)); REFINE],
        cell: &[f32; MAX_CONTROL_DEGREE],
        steps: usize,
    ) {
        for lengths_k in 0..REFINE.pow(grid.free as u32) {
            let mut kk = lengths_k;
            let mut sub = *cell;
            for f in sub.iter_mut().take(grid.free) {
                *f += refined_offset(kk % REFINE) / steps as f32;
                kk /= REFINE;
            }
            for &(h, h_sc) in turned {
                self.probe(grid, h, h_sc, &sub);
            }
        }
    }

    /// One probe: the free pieces at fractions `cell` of their caps, completed onto the target;
    /// returns the largest clearance among the completions (how near the probe came to
    /// feasible). The heading's (sin, cos) are carried from piece to piece (the same bits as
    /// computing them afresh).
    fn probe(
        &mut self,
        grid: &FreeGrid,
        heading: f32,
        heading_sc: (f32, f32),
        cell: &[f32; MAX_CONTROL_DEGREE],
    ) -> f32 {
        let (r, dist, n, free) = (self.p.radius, self.plane.dist, self.pieces.len(), grid.free);
        let mut lengths = [0.0f32; MAX_CONTROL_DEGREE];
        let mut pose = Pose {
            x: 0.0,
            y: 0.0,
            psi: heading,
        };
        let mut sc = heading_sc;
        for i in 0..free {
            let piece = &self.pieces[i];
            lengths[i] = grid.caps[i] * cell[i];
            (pose, sc) = advance_from(pose, sc, piece.kind, lengths[i], piece.side, r);
        }
        // The last two pieces are at least as long as the straight line to the target (less a
        // margin far above the rounding of the completions), and D >= 0: when that bounds F at or
        // above the sink's bound, every completion would be refused.
        // (No bound yet, as at the start of a sweep: nothing to test.)
        let limit = self.bound;
        if limit < f32::INFINITY {
            let free_length: f32 = lengths[..free].iter().sum();
            let (dx, dy) = (dist - pose.x, -pose.y);
            let rest = crate::fmath::sqrt(dx * dx + dy * dy) * (1.0 - 1e-4);
            if self.p.scenario.weights.length * (free_length + rest) + self.fixed >= limit {
                return f32::NEG_INFINITY;
            }
        }
        let mut nearest = f32::NEG_INFINITY;
        complete(pose, sc, &grid.tail, dist, r, &mut |la, lb| {
            lengths[n - 2] = la;
            lengths[n - 1] = lb;
            nearest = crate::fmath::max(nearest, self.emit(heading, heading_sc, &lengths));
        });
        nearest
    }
}

/// The upper bound (radius-lengths) of each segment of `piece`.
fn segment_upper(p: &Problem, piece: &Piece) -> f32 {
    p.upper[p.length_var(piece.segments.trailing_zeros() as usize)]
}

/// The problem variables of the planar path of `heading` and `piece_lengths` (each piece's
/// length shared equally among its segments).
fn planar_variables(
    p: &Problem,
    plane: &SweepPlane,
    pieces: &Pieces,
    heading: f32,
    piece_lengths: &[f32; MAX_CONTROL_DEGREE],
) -> Option<Vars> {
    let mut lengths = [0.0f32; MAX_CONTROL_DEGREE];
    for (piece, len) in pieces.iter().zip(piece_lengths) {
        for (i, l) in lengths.iter_mut().enumerate() {
            if piece.segments & (1 << i) != 0 {
                *l = len / f32::from(piece.count);
            }
        }
    }
    plane.variables(p, &PlanarPath { heading, lengths })
}

/// The grid a form of two pieces or more is swept over: headings, and the lengths of the free
/// pieces (all but the last two) as fractions of their caps; the last two pieces are completed
/// onto the target in closed form.
struct FreeGrid {
    /// The last two pieces.
    tail: Tail,
    /// The longest each free piece is swept to (mm).
    caps: [f32; MAX_CONTROL_DEGREE],
    /// How many pieces are free.
    free: usize,
    /// Headings of the grid (the two at the tilt bound come on top).
    headings: usize,
    /// Lengths per free piece.
    steps: usize,
    /// Radians between the grid's headings.
    heading_step: f32,
}

impl FreeGrid {
    /// The grid of `pieces` (at least two) in `plane`.
    fn new(p: &Problem, plane: &SweepPlane, pieces: &Pieces) -> Option<Self> {
        let r = p.radius;
        let n = pieces.len();
        // The last two pieces, completed onto the target. Those that are arcs which may turn by
        // at most half a circle have their completions that turn further left out unseen (`emit`
        // would refuse them).
        let half_turn = |piece: &Piece| {
            piece.kind == SegmentKind::Arc
                && segment_upper(p, piece) * f32::from(piece.count) <= core::f32::consts::PI
        };
        let [.., a, b] = pieces.as_slice() else {
            return None;
        };
        let tail = Tail {
            kinds: (a.kind, b.kind),
            sides: (a.side, b.side),
            half_turn_at_most: (half_turn(a), half_turn(b)),
        };
        let (headings, steps) = grid(n);
        let free = n - 2;
        let max_free = 1.25 * plane.dist;
        let mut caps = [0.0f32; MAX_CONTROL_DEGREE];
        for (c, piece) in caps.iter_mut().zip(pieces).take(free) {
            *c = match piece.kind {
                SegmentKind::Arc => {
                    (segment_upper(p, piece) * r * f32::from(piece.count)).min(max_free)
                }
                SegmentKind::Line => max_free,
            };
        }
        Some(FreeGrid {
            tail,
            caps,
            free,
            headings,
            steps,
            heading_step: 2.0 * HEADING_SPAN / headings as f32,
        })
    }

    /// Heading `hi` of the grid (from the chord, radians), then the two at the tilt bound, if
    /// the plane crosses it.
    fn heading(&self, plane: &SweepPlane, hi: usize) -> Option<f32> {
        if hi < self.headings {
            Some(-HEADING_SPAN + self.heading_step * (hi as f32 + 0.5))
        } else {
            plane.tilt_bound_headings.get(hi - self.headings).copied()
        }
    }
}

/// Offset of a refined cell's point `k` along one dimension of the cell, in cell widths.
fn refined_offset(k: usize) -> f32 {
    (k as f32 + 0.5) / REFINE as f32 - 0.5
}

/// The headings of a refined cell about `heading`, with their (sin, cos).
// Not inlined: the compiler would otherwise take these sines for every probe of the grid, in
// case the probe is refined.
#[inline(never)]
fn refined_headings(heading: f32, heading_step: f32) -> [(f32, (f32, f32)); REFINE] {
    let mut out = [(0.0, (0.0, 0.0)); REFINE];
    for (k, o) in out.iter_mut().enumerate() {
        let h = heading + heading_step * refined_offset(k);
        *o = (h, crate::fmath::sincos(h));
    }
    out
}

/// How much finer the lengths are gridded on the tilt-bound headings.
const BOUND_FINER: usize = 4;
/// Subdivisions per dimension of a refined cell.
const REFINE: usize = 4;

#[cfg(test)]
mod tests;
