//! The target as imaging sees it: a filter of its position that lets it drift (the tissue moves as
//! the needle pushes it, DiMaio & Salcudean 2003) and follows a jump instead of rejecting it for
//! ever. A fix far outside what the filter expects is an outlier once; when the next fixes agree
//! with it and not with the estimate, the target has moved: the filter starts again from them and
//! says so, so a moved target is either followed or ends the run with a stop the controller
//! reports (the continuation to the new target fails its check), never ignored in silence.

use crate::model::kinematics::V3;

/// Innovations beyond this many standard deviations (squared, summed over the axes) are
/// outliers: about 5 sigma for three axes (the tip's gate).
const GATE: f32 = 25.0;

/// Consecutive fixes outside the gate, agreeing with one another, that make a jump: one is an
/// outlier, three that agree are a target that moved.
pub const JUMP_FIXES: u8 = 3;

/// How one imaged target was used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetFix {
    /// Fused into the estimate.
    Fused,
    /// Outside the gate: not used (yet).
    Outlier,
    /// The last [`JUMP_FIXES`] fixes agreed with one another and not with the estimate: the
    /// estimate restarted from their mean.
    Jumped,
}

/// The filter's state beside the estimated position.
#[derive(Clone, Copy, Debug)]
pub struct TargetFilter {
    /// Variance of the estimate, per axis (mm²).
    pub var: f32,
    /// Random walk of the target per millimetre of insertion (mm² per mm).
    walk_var_per_mm: f32,
    /// Consecutive fixes outside the gate, their sum and the first of them.
    rejected: u8,
    rejected_sum: V3,
    first_rejected: V3,
}

impl TargetFilter {
    /// The prior: `sd` per axis, drifting by `walk_mm` per square-root millimetre.
    pub fn new(sd: f32, walk_mm: f32) -> TargetFilter {
        TargetFilter {
            var: sd * sd,
            walk_var_per_mm: walk_mm * walk_mm,
            rejected: 0,
            rejected_sum: V3::zeros(),
            first_rejected: V3::zeros(),
        }
    }

    /// The needle went `length` mm further: the target may have drifted.
    pub fn advanced(&mut self, length: f32) {
        if length > 0.0 {
            self.var += self.walk_var_per_mm * length;
        }
    }

    /// Fuses the imaged target `z` (noise variance `r` per axis) into the estimate `target`.
    pub fn fuse(&mut self, target: &mut V3, z: V3, r: f32) -> TargetFix {
        let y = z - *target;
        let s = self.var + r;
        if y.dot(&y) / s <= GATE {
            self.rejected = 0;
            let k = self.var / s;
            *target += y * k;
            self.var *= 1.0 - k;
            return TargetFix::Fused;
        }
        // Two fixes of one still target differ by noise of variance 2r per axis.
        let agrees = self.rejected > 0 && {
            let d = z - self.first_rejected;
            d.dot(&d) / (2.0 * r) <= GATE
        };
        if agrees {
            self.rejected += 1;
            self.rejected_sum += z;
        } else {
            self.rejected = 1;
            self.rejected_sum = z;
            self.first_rejected = z;
        }
        if self.rejected < JUMP_FIXES {
            return TargetFix::Outlier;
        }
        let n = f32::from(self.rejected);
        *target = self.rejected_sum / n;
        self.var = r / n;
        self.rejected = 0;
        TargetFix::Jumped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_single_far_fix_is_an_outlier_and_changes_nothing() {
        let mut f = TargetFilter::new(0.5, 0.05);
        let mut t = V3::new(0.0, 0.0, 100.0);
        assert_eq!(
            f.fuse(&mut t, V3::new(6.0, 0.0, 100.0), 0.25),
            TargetFix::Outlier
        );
        assert_eq!(t, V3::new(0.0, 0.0, 100.0));
        // The next fix agrees with the estimate: the run of rejections is over.
        assert_eq!(
            f.fuse(&mut t, V3::new(0.1, 0.0, 100.0), 0.25),
            TargetFix::Fused
        );
        assert_eq!(
            f.fuse(&mut t, V3::new(6.0, 0.0, 100.0), 0.25),
            TargetFix::Outlier
        );
        assert_eq!(
            f.fuse(&mut t, V3::new(6.0, 0.1, 100.0), 0.25),
            TargetFix::Outlier
        );
    }

    #[test]
    fn a_target_that_moved_is_followed_after_three_agreeing_fixes() {
        let mut f = TargetFilter::new(0.5, 0.05);
        let mut t = V3::new(0.0, 0.0, 100.0);
        for _ in 0..50 {
            assert_eq!(
                f.fuse(&mut t, V3::new(0.0, 0.0, 100.0), 0.25),
                TargetFix::Fused
            );
        }
        let moved = [
            V3::new(5.1, 0.0, 100.0),
            V3::new(4.9, 0.1, 100.0),
            V3::new(5.0, -0.1, 100.0),
        ];
        assert_eq!(f.fuse(&mut t, moved[0], 0.25), TargetFix::Outlier);
        assert_eq!(f.fuse(&mut t, moved[1], 0.25), TargetFix::Outlier);
        assert_eq!(f.fuse(&mut t, moved[2], 0.25), TargetFix::Jumped);
        assert!((t - V3::new(5.0, 0.0, 100.0)).norm() < 1e-5, "{t:?}");
        // The restarted estimate fuses the next fix near the new place.
        assert_eq!(
            f.fuse(&mut t, V3::new(5.2, 0.0, 100.0), 0.25),
            TargetFix::Fused
        );
    }

    #[test]
    fn scattered_far_fixes_are_outliers_not_a_jump() {
        let mut f = TargetFilter::new(0.5, 0.05);
        let mut t = V3::new(0.0, 0.0, 100.0);
        for x in [6.0, -6.0, 0.0] {
            let z = V3::new(x, if x == 0.0 { 8.0 } else { 0.0 }, 100.0);
            assert_eq!(f.fuse(&mut t, z, 0.25), TargetFix::Outlier);
        }
        assert_eq!(t, V3::new(0.0, 0.0, 100.0));
    }

    #[test]
    fn the_walk_keeps_a_slow_drift_inside_the_gate() {
        // The target drifts 4 mm over 20 mm of insertion, one fix per millimetre: with the walk
        // the filter follows it fix by fix; without it, the estimate freezes and the drift
        // leaves the gate.
        let follow = |walk: f32| {
            let mut f = TargetFilter::new(0.5, walk);
            let mut t = V3::new(0.0, 0.0, 100.0);
            for _ in 0..200 {
                f.advanced(1.0);
                f.fuse(&mut t, V3::new(0.0, 0.0, 100.0), 0.25);
            }
            let mut outcomes = [0; 3];
            for i in 1..=20 {
                f.advanced(1.0);
                let z = V3::new(0.2 * i as f32, 0.0, 100.0);
                outcomes[f.fuse(&mut t, z, 0.25) as usize] += 1;
            }
            (outcomes, t.x)
        };
        let (with_walk, x) = follow(0.1);
        assert_eq!(with_walk, [20, 0, 0]);
        assert!(x > 2.5, "{x}");
        let (without, _) = follow(1e-4);
        assert!(without[1] + without[2] > 0, "{without:?}");
    }
}
