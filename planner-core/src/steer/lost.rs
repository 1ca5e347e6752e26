//! The estimate that may have lost the tip: position fixes the gate keeps rejecting.

/// Position fixes rejected in a row after which the estimate counts as possibly lost, when the
/// fixes it does fuse are already inconsistent ([`LOST_CONSISTENCY`]). Two in a row (tried
/// first) left 5 and 4 collisions in 1 000 at twice the world (paper-clinical, space-clinical):
/// between two rejections an accepted fix from the gate's edge reset the count.
const LOST_AFTER: u8 = 1;

/// The fused fixes' running consistency (squared innovation per axis against what the model
/// expects) above which a rejected fix means a lost tip rather than a glitch: twice the model's
/// noise variance, a world the model does not describe. In the clinical world a rejected fix
/// rarely comes with it (0.1-0.6 % of runs stop by it, docs/execution.md); at twice the world
/// nearly every run passes it.
pub const LOST_CONSISTENCY: f32 = 2.0;

/// The position fixes rejected since the last one fused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rejected {
    in_a_row: u8,
    /// The largest innovation among them (mm): how far the tracker put the tip from the
    /// estimate.
    largest: f32,
}

impl Rejected {
    /// None rejected (after a fused fix).
    pub const NONE: Rejected = Rejected {
        in_a_row: 0,
        largest: 0.0,
    };

    /// A fix `offset` mm from the estimate was rejected.
    pub fn rejected(&mut self, offset: f32) {
        self.in_a_row = self.in_a_row.saturating_add(1);
        if offset.is_finite() {
            self.largest = self.largest.max(offset);
        }
    }

    /// How far the tip may be from the estimate (mm): after [`LOST_AFTER`] rejected in a row,
    /// the largest of their innovations (the caller asks only when [`LOST_CONSISTENCY`] is
    /// passed) (the tracker puts the tip there, and the estimate
    /// cannot tell which is right); 0 otherwise.
    ///
    /// Why: in a world rougher than the model (layers bending twice as hard as the plan, a
    /// tracker twice as noisy) the estimate can lose the tip: the fixes fail the gate, dead
    /// reckoning carries the estimate away, and runs touched an obstacle before the gap
    /// without a fix ended them as tracking lost (docs/execution.md, "Twice the world").
    pub fn offset(&self) -> f32 {
        if self.in_a_row >= LOST_AFTER {
            self.largest
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fused_fix_forgets_the_rejected_ones() {
        let mut r = Rejected::NONE;
        assert_eq!(r.offset(), 0.0);
        r.rejected(3.0);
        r.rejected(f32::NAN);
        r.rejected(2.0);
        assert_eq!(r.offset(), 3.0);
        r = Rejected::NONE;
        assert_eq!(r.offset(), 0.0);
    }
}
