//! The estimate that may have lost the tip: position fixes the gate keeps rejecting.

use crate::model::kinematics::V3;

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

/// How far a fix `y` (its innovation) puts the tip off the path the estimate is on, heading
/// `e3`: its part across the heading, and its part ahead. Why not behind: a tip held back at a
/// membrane while the needle is pushed (a stall, then a jump once it punctures) lags along the
/// path already travelled, whose clearance was kept; counting that lag stopped paper-clinical runs
/// as tracking lost after stalls of 4 to 15 mm (docs/execution.md, "When nothing reaches").
pub(super) fn off_the_path(y: V3, e3: V3) -> f32 {
    let ahead = y.dot(&e3);
    (y - e3 * ahead).norm() + ahead.max(0.0)
}

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

    /// A fix behind the tip along its heading (a stall) is off the path by its part across;
    /// one ahead or across counts whole.
    #[test]
    fn a_fix_behind_along_the_heading_is_on_the_path() {
        let e3 = V3::new(0.0, 0.6, 0.8);
        let across = V3::new(1.0, 0.0, 0.0);
        assert!(off_the_path(-5.0 * e3, e3).abs() < 1e-6);
        assert!((off_the_path(-5.0 * e3 + 0.5 * across, e3) - 0.5).abs() < 1e-6);
        assert!((off_the_path(5.0 * e3, e3) - 5.0).abs() < 1e-6);
        assert!((off_the_path(3.0 * across + 4.0 * e3, e3) - 7.0).abs() < 1e-6);
    }

    /// An estimate whose fixes already disagree with its model (a tracker three times as noisy
    /// as told): a fix 6 mm behind along the heading is rejected, yet leaves the tip on the path
    /// travelled (no offset to keep clear); one 6 mm across puts it that far off.
    #[test]
    fn a_stalled_tip_is_not_a_lost_one() {
        use crate::estimate::{Estimate, NoiseModel};
        use crate::model::form::SegmentKind;
        use crate::model::kinematics::Frame;
        let noise = NoiseModel::DEFAULT;
        let start = Frame {
            p: V3::zeros(),
            r: nalgebra::Matrix3::identity(),
        };
        let mut e = Estimate::new(start, V3::new(0.0, 0.0, 90.0), &noise);
        let mut truth = start;
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut noisy = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Uniform on (-1, 1) times 3 sqrt(3) sd: variance 9 times the model's.
            let u = ((x >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0;
            u * 3.0 * 1.732 * noise.position_mm
        };
        for _ in 0..30 {
            e.advanced(SegmentKind::Line, 1.0, 63.7);
            truth = truth.advanced(SegmentKind::Line, 1.0, 63.7);
            let _ = e.fuse_position(truth.p + V3::new(noisy(), noisy(), noisy()));
        }
        let mut lagging = e.clone();
        assert!(!lagging.fuse_position(e.tip.p - 6.0 * e.tip.e3()));
        assert!(lagging.lost_offset() < 0.5, "{}", lagging.lost_offset());
        let mut across = e.clone();
        assert!(!across.fuse_position(e.tip.p + V3::new(6.0, 0.0, 0.0)));
        assert!(across.lost_offset() > 5.5, "{}", across.lost_offset());
    }
}
