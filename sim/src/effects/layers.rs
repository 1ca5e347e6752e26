//! Layered tissue: boundaries along the insertion, a curvature factor per layer, and a puncture
//! at each boundary (the tip stalls while the robot keeps inserting, then catches up at once).
//!
//! [`Layers::advance`] turns the advance the tip would make in a homogeneous tissue into the
//! moves it makes here; the world executes them (each with its layer's curvature factor).

use crate::factor::MIN_FACTOR;
use crate::random::{Draw, SplitMix64};
use serde::Serialize;

/// One move of the tip: `length` mm along the needle's path with its curvature multiplied by
/// `factor`; a `jump` is the release after a stall (no reading is taken within it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// Length (mm).
    pub length: f32,
    /// Curvature factor of the layer the move is in.
    pub factor: f32,
    /// The membrane gave: the tip catches up the stalled insertion at once.
    pub jump: bool,
}

/// The layers of one run and where the tip is among them.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Layers {
    /// Depths of the boundaries along the tip's path (mm), ascending.
    pub boundaries_mm: Vec<f32>,
    /// Curvature factor of the layer behind each boundary.
    pub factors: Vec<f32>,
    /// Insertion each boundary stalls the tip for (mm).
    pub stalls_mm: Vec<f32>,
    /// The next boundary the tip reaches (or is stalled at).
    #[serde(skip)]
    next: usize,
    /// Insertion still to absorb before the membrane at `next` gives (mm; 0: not stalled).
    #[serde(skip)]
    stall_left: f32,
    /// Insertion absorbed by the stall so far: the jump at the release (mm).
    #[serde(skip)]
    owed: f32,
}

impl Layers {
    /// `count` boundaries uniform over (0, `length_mm`) of depth (or at `given`), each
    /// layer's factor 1 + N(0, `spread`) (at least [`MIN_FACTOR`]), each stall exponential of
    /// mean `puncture_mm`.
    pub fn draw(
        g: &mut SplitMix64,
        count: u8,
        given: Option<&[f32]>,
        length_mm: f32,
        (spread, puncture_mm): (f32, f32),
    ) -> Layers {
        let mut boundaries_mm: Vec<f32> = match given {
            Some(depths) => depths.to_vec(),
            None => (0..count)
                .map(|_| g.range(0.0, f64::from(length_mm.max(0.0))) as f32)
                .collect(),
        };
        boundaries_mm.sort_by(f32::total_cmp);
        let count = boundaries_mm.len();
        let factors = (0..count)
            .map(|_| (1.0 + g.normal(f64::from(spread)) as f32).max(MIN_FACTOR))
            .collect();
        let stalls_mm = (0..count)
            .map(|_| {
                // Exponential by inversion; 1 - u lies in (0, 1], so the logarithm is finite.
                let u = 1.0 - g.unit();
                (-f64::from(puncture_mm) * libm::log(u)) as f32
            })
            .collect();
        Layers::given(boundaries_mm, factors, stalls_mm)
    }

    /// Layers at the given boundaries (ascending), with their factors and stalls.
    pub fn given(boundaries_mm: Vec<f32>, factors: Vec<f32>, stalls_mm: Vec<f32>) -> Layers {
        Layers {
            boundaries_mm,
            factors,
            stalls_mm,
            next: 0,
            stall_left: 0.0,
            owed: 0.0,
        }
    }

    /// The curvature factor where the tip is (1 before the first boundary is punctured).
    pub fn factor(&self) -> f32 {
        match self.next.checked_sub(1) {
            Some(i) => self.factors.get(i).copied().unwrap_or(1.0),
            None => 1.0,
        }
    }

    /// The curvature factor of the layer at `depth` mm along the tip's path (1 before the first
    /// boundary), whatever the tip has punctured so far.
    pub fn factor_at(&self, depth: f32) -> f32 {
        let behind = self
            .boundaries_mm
            .iter()
            .take_while(|b| **b <= depth)
            .count();
        behind
            .checked_sub(1)
            .map_or(1.0, |i| self.factors.get(i).copied().unwrap_or(1.0))
    }

    /// Whether the tip is held at a boundary.
    pub fn stalled(&self) -> bool {
        self.stall_left > 0.0
    }

    /// The moves of the tip for an advance of `a` mm (what it would make in homogeneous
    /// tissue) from depth `depth`, appended to `moves`.
    pub fn advance(&mut self, depth: f32, a: f32, moves: &mut Vec<Move>) {
        let (mut left, mut d) = (a.max(0.0), depth);
        while left > 0.0 {
            if self.stalled() {
                if left < self.stall_left {
                    self.stall_left -= left;
                    self.owed += left;
                    return;
                }
                left -= self.stall_left;
                let jump = self.owed + self.stall_left;
                self.stall_left = 0.0;
                self.owed = 0.0;
                self.next += 1;
                moves.push(Move {
                    length: jump,
                    factor: self.factor(),
                    jump: true,
                });
                d += jump;
                continue;
            }
            let to_boundary = self.boundaries_mm.get(self.next).map(|b| b - d);
            match to_boundary {
                Some(gap) if gap <= left => {
                    let gap = gap.max(0.0);
                    if gap > 0.0 {
                        moves.push(self.plain(gap));
                    }
                    d += gap;
                    left -= gap;
                    let stall = self.stalls_mm.get(self.next).copied().unwrap_or(0.0);
                    if stall > 0.0 {
                        self.stall_left = stall;
                    } else {
                        self.next += 1;
                    }
                }
                _ => {
                    moves.push(self.plain(left));
                    left = 0.0;
                }
            }
        }
    }

    fn plain(&self, length: f32) -> Move {
        Move {
            length,
            factor: self.factor(),
            jump: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total(moves: &[Move]) -> f32 {
        moves.iter().map(|m| m.length).sum()
    }

    /// A boundary at 2.5 mm stalling 1.7 mm: the tip stops there for 1.7 mm of insertion, then
    /// jumps; the insertion is all made good, and the layer's factor applies after it.
    #[test]
    fn a_stall_then_a_jump() {
        let mut l = Layers::given(vec![2.5], vec![1.5], vec![1.7]);
        let mut depth = 0.0;
        let mut moves = Vec::new();
        let mut seen = Vec::new();
        for _ in 0..6 {
            moves.clear();
            l.advance(depth, 1.0, &mut moves);
            depth += total(&moves);
            seen.push((depth, l.stalled(), l.factor()));
        }
        assert_eq!(seen[1], (2.0, false, 1.0));
        assert_eq!(seen[2], (2.5, true, 1.0), "held at the boundary");
        assert_eq!(seen[3], (2.5, true, 1.0));
        assert!((seen[4].0 - 5.0).abs() < 1e-5, "caught up: {:?}", seen[4]);
        assert_eq!((seen[4].1, seen[4].2), (false, 1.5));
        assert!((seen[5].0 - 6.0).abs() < 1e-5);
    }

    #[test]
    fn draws_are_sorted_floored_and_of_the_count() {
        let mut g = crate::random::seeded(4);
        let l = Layers::draw(&mut g, 5, None, 80.0, (2.0, 1.0));
        assert_eq!(l.boundaries_mm.len(), 5);
        assert!(l.boundaries_mm.windows(2).all(|w| w[0] <= w[1]));
        assert!(l.boundaries_mm.iter().all(|b| (0.0..80.0).contains(b)));
        assert!(l.factors.iter().all(|f| *f >= MIN_FACTOR));
        assert!(l.stalls_mm.iter().all(|s| s.is_finite() && *s >= 0.0));
    }
}
