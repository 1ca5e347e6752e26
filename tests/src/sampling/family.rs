//! The completeness check's scenarios: seeded random 3-D scenarios at a chosen tilt bound.

use crate::reference::random::random_scenario;
use planner_core::Scenario;

/// Control degree N of every scenario of the family.
pub const DEGREE: u8 = 4;

/// The scenario of `seed` at the tilt bound `tilt_deg`: the space scenario of
/// [`random_scenario`] for the same seed (entry at the origin heading +z; target at x in
/// [-25, 25), y in [-30, 30), z in [60, 110) mm, tolerance 0.1 mm; 3 to 8 spheres of radius 4 to
/// 13 mm centred near the entry-target line, at 15 % to 85 % of the way, up to 30 mm (x), 35 mm
/// (y) and 10 mm (z) off it, each clear of the entry and the target by 3 mm; arc radius 63.7 mm or,
/// for about half the seeds, drawn in [45, 100) mm; arcs of at most 180 degrees, lines of the
/// default bound), with N = 4, F = length (the risk and control weights 0) and the tilt bound set
/// to `tilt_deg`.
pub fn completeness_scenario(seed: u64, tilt_deg: f32) -> Scenario {
    let mut s = random_scenario(seed, false);
    s.options.max_control_degree = DEGREE;
    s.weights.risk = 0.0;
    s.weights.control = 0.0;
    s.entry.max_tilt_deg = tilt_deg;
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenarios_are_valid_repeatable_and_length_only() {
        for seed in 0..30 {
            for tilt in [0.0, 2.0, 10.0, 60.0] {
                let s = completeness_scenario(seed, tilt);
                assert_eq!(s.validate(), Ok(()), "seed {seed} tilt {tilt}");
                assert_eq!(s, completeness_scenario(seed, tilt));
                assert_eq!(s.entry.max_tilt_deg, tilt);
                assert_eq!((s.weights.risk, s.weights.control), (0.0, 0.0));
                assert_eq!(s.options.max_control_degree, 4);
            }
        }
    }
}
