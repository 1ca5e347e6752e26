//! A steered insertion in pieces, as the driver board executes it: each step of the controller's
//! continuation is cut into pieces of at most `piece_mm` of commanded insertion (a rotation is
//! one piece), the board moves one piece, and the tracker's reading after it may replace the
//! rest. The board and the host that mirrors it cut the same pieces from the same steps, so the
//! host knows what each piece was without being told.
//!
//! A piece of a push is its share of the step's length (the cumulative share, as the simulated
//! world takes its pieces, so rounding never accumulates); a piece of a spun push carries whole
//! pairs of turns, so the shaft is back where it began at every piece's end and a replacement
//! turns from there (a spin's pieces may be longer than `piece_mm`), a duty-cycled piece the
//! step's duty (the board's cycles of one are even). The commanded depth and base roll are kept exactly as the schedule counts them.
//!
//! ```
//! use planner_core::execute::pieces::Pieces;
//! use planner_core::execute::schedule::{Op, Step};
//!
//! let steps = [
//!     Step { op: Op::Rotate { angle_deg: 90.0 }, duration_s: 0.25 },
//!     Step { op: Op::Insert { length_mm: 2.5 }, duration_s: 1.0 },
//! ];
//! let mut pieces = Pieces::new(&steps, 1.0).unwrap();
//! let mut lengths = [0.0f32; 4];
//! let mut n = 0;
//! while let Some(piece) = pieces.next_piece() {
//!     lengths[n] = piece.op.inserted_mm();
//!     n += 1;
//! }
//! assert_eq!(n, 4); // the rotation, then three pieces of the 2.5 mm push
//! assert_eq!(pieces.base_deg(), 90.0);
//! assert!((pieces.depth_mm() - 2.5).abs() < 1e-6);
//! ```

use super::perturbation::MAX_PIECE_MM;
use super::schedule::{Op, Step, Steps};

/// Why pieces cannot be cut.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PiecesError {
    /// `piece_mm` is not finite, not above 0 or above [`MAX_PIECE_MM`].
    BadPieceLength,
    /// More steps than a continuation holds.
    TooManySteps,
}

/// The pieces of a continuation, and where the commanded insertion stands.
#[derive(Clone, Debug, PartialEq)]
pub struct Pieces {
    steps: Steps,
    piece_mm: f32,
    /// The step being cut (an index into `steps`).
    step: usize,
    /// Pieces of that step done, and how many it has.
    done: u32,
    of: u32,
    depth_mm: f32,
    base_deg: f32,
    /// Pieces handed out since the start, and the last of them.
    count: u32,
    last: Option<Step>,
}

impl Pieces {
    /// The pieces of `steps`, each at most `piece_mm` of insertion, from depth 0 and base roll 0.
    pub fn new(steps: &[Step], piece_mm: f32) -> Result<Pieces, PiecesError> {
        if !(piece_mm.is_finite() && piece_mm > 0.0 && piece_mm <= MAX_PIECE_MM) {
            return Err(PiecesError::BadPieceLength);
        }
        let mut p = Pieces {
            steps: Steps::new(),
            piece_mm,
            step: 0,
            done: 0,
            of: 0,
            depth_mm: 0.0,
            base_deg: 0.0,
            count: 0,
            last: None,
        };
        p.replace(steps)?;
        Ok(p)
    }

    /// What is left is replaced by `steps`, from where the last piece ended.
    pub fn replace(&mut self, steps: &[Step]) -> Result<(), PiecesError> {
        self.steps = Steps::from_slice(steps).map_err(|_| PiecesError::TooManySteps)?;
        self.step = 0;
        self.done = 0;
        self.of = self
            .steps
            .first()
            .map_or(0, |s| pieces_of(s, self.piece_mm));
        Ok(())
    }

    /// The next piece as a step of its own (its share of the step's duration), or `None` when
    /// the continuation has run out.
    pub fn next_piece(&mut self) -> Option<Step> {
        while self.done >= self.of {
            self.step += 1;
            self.done = 0;
            self.of = pieces_of(self.steps.get(self.step)?, self.piece_mm);
        }
        let step = *self.steps.get(self.step)?;
        let (k, n) = (self.done + 1, self.of);
        let share = |v: f32| v * (k as f32 / n as f32) - v * ((k - 1) as f32 / n as f32);
        let op = match step.op {
            Op::Rotate { angle_deg } => Op::Rotate { angle_deg },
            Op::Insert { length_mm } => Op::Insert {
                length_mm: share(length_mm),
            },
            Op::InsertSpin { length_mm, turns } => Op::InsertSpin {
                length_mm: share(length_mm),
                turns: whole_share(turns, k, n),
            },
            Op::InsertDuty { length_mm, duty } => Op::InsertDuty {
                length_mm: share(length_mm),
                duty,
            },
        };
        self.done = k;
        self.count = self.count.saturating_add(1);
        self.depth_mm += op.inserted_mm();
        if let Op::Rotate { angle_deg } = op {
            self.base_deg += angle_deg;
        }
        let piece = Step {
            op,
            duration_s: share(step.duration_s),
        };
        self.last = Some(piece);
        Some(piece)
    }

    /// The last piece handed out.
    pub fn last(&self) -> Option<Step> {
        self.last
    }

    /// Whether no piece is left.
    pub fn is_done(&self) -> bool {
        self.step >= self.steps.len() || self.done >= self.of && self.step + 1 >= self.steps.len()
    }

    /// The commanded insertion from the entry after the pieces handed out (mm).
    pub fn depth_mm(&self) -> f32 {
        self.depth_mm
    }

    /// The commanded base roll from the posture's after the pieces handed out (degrees; a spin's
    /// whole turns leave it).
    pub fn base_deg(&self) -> f32 {
        self.base_deg
    }

    /// Pieces handed out since the start.
    pub fn count(&self) -> u32 {
        self.count
    }
}

/// Pieces `step` is cut into.
fn pieces_of(step: &Step, piece_mm: f32) -> u32 {
    let by_length = |len: f32| libm::ceilf(libm::fabsf(len) / piece_mm).clamp(1.0, 1e6) as u32;
    match step.op {
        Op::Rotate { .. } => 1,
        Op::Insert { length_mm } | Op::InsertDuty { length_mm, .. } => by_length(length_mm),
        Op::InsertSpin { length_mm, turns } => by_length(length_mm).min(turns / 2).max(1),
    }
}

/// Whole turns of piece `k` of `n` of a spin of `turns`: pairs of turns (the cumulative share,
/// rounded down), so that each piece ends where the shaft began, the last piece the odd one.
fn whole_share(turns: u32, k: u32, n: u32) -> u32 {
    let pairs = |k: u32| (u64::from(turns / 2) * u64::from(k) / u64::from(n.max(1))) as u32;
    let odd = if k == n { turns % 2 } else { 0 };
    2 * (pairs(k) - pairs(k - 1)) + odd
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(op: Op) -> Step {
        Step {
            op,
            duration_s: 2.0,
        }
    }

    fn all(p: &mut Pieces) -> heapless::Vec<Step, 64> {
        let mut out = heapless::Vec::new();
        while let Some(s) = p.next_piece() {
            out.push(s).unwrap();
        }
        out
    }

    #[test]
    fn pushes_are_cut_at_most_a_piece_long_and_sum_to_the_step() {
        let steps = [
            step(Op::Insert { length_mm: 3.2 }),
            step(Op::InsertDuty {
                length_mm: 0.4,
                duty: 0.5,
            }),
        ];
        let mut p = Pieces::new(&steps, 1.0).unwrap();
        let pieces = all(&mut p);
        assert_eq!(pieces.len(), 5);
        assert!(pieces.iter().all(|s| s.op.inserted_mm() <= 1.0));
        let pushed: f32 = pieces[..4].iter().map(|s| s.op.inserted_mm()).sum();
        assert!((pushed - 3.2).abs() < 1e-5);
        let time: f32 = pieces[..4].iter().map(|s| s.duration_s).sum();
        assert!((time - 2.0).abs() < 1e-5);
        assert_eq!(pieces[4].op, steps[1].op);
        assert!(p.is_done());
        assert!((p.depth_mm() - 3.6).abs() < 1e-5);
    }

    #[test]
    fn a_spin_is_cut_into_whole_turns() {
        let steps = [step(Op::InsertSpin {
            length_mm: 5.0,
            turns: 7,
        })];
        let pieces = all(&mut Pieces::new(&steps, 1.0).unwrap());
        assert_eq!(pieces.len(), 3);
        let turns: heapless::Vec<u32, 3> = pieces
            .iter()
            .map(|s| match s.op {
                Op::InsertSpin { turns, .. } => turns,
                _ => 0,
            })
            .collect();
        assert_eq!(&turns[..], &[2, 2, 3]);
    }

    #[test]
    fn a_replacement_starts_where_the_last_piece_ended() {
        let steps = [
            step(Op::Rotate { angle_deg: -30.0 }),
            step(Op::Insert { length_mm: 4.0 }),
        ];
        let mut p = Pieces::new(&steps, 0.5).unwrap();
        p.next_piece();
        p.next_piece();
        assert_eq!(p.base_deg(), -30.0);
        p.replace(&[step(Op::Rotate { angle_deg: 10.0 })]).unwrap();
        assert!(!p.is_done());
        assert_eq!(
            p.next_piece().map(|s| s.op),
            Some(Op::Rotate { angle_deg: 10.0 })
        );
        assert!(p.is_done());
        assert_eq!(p.next_piece(), None);
        assert_eq!(p.base_deg(), -20.0);
        assert_eq!(p.depth_mm(), 0.5);
        assert_eq!(p.count(), 3);
    }

    #[test]
    fn bad_piece_lengths_and_empty_lists() {
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1.5] {
            assert_eq!(Pieces::new(&[], bad), Err(PiecesError::BadPieceLength));
        }
        let mut p = Pieces::new(&[], 1.0).unwrap();
        assert!(p.is_done());
        assert_eq!(p.next_piece(), None);
    }
}
