//! Seeded random scenarios for the optimality comparison: 3 to 8 obstacles between the entry and
//! the target, none containing either (with a margin), in the y-z plane or in space.

use needle_sim::random::{seeded, Draw};
use planner_core::model::scenario::{Obstacle, Workspace};
use planner_core::Scenario;

/// Margin kept between an obstacle's surface and the entry or the target (mm).
pub const MARGIN: f64 = 3.0;

/// A random scenario: `plane` puts everything in the y-z plane (circles, the paper's setting),
/// otherwise spheres off it. The needle, weights and bounds vary around the paper's.
pub fn random_scenario(seed: u64, plane: bool) -> Scenario {
    let mut rng = seeded(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ u64::from(plane));
    let mut s = Scenario::paper();
    s.options.workspace = if plane {
        Workspace::PlaneYz
    } else {
        Workspace::Space
    };
    s.options.max_control_degree = 3;
    // Half the scenarios keep the paper's needle and weights; the others vary them.
    if rng.unit() < 0.5 {
        s.needle.curvature_radius = rng.range(45.0, 100.0) as f32;
        s.entry.max_tilt_deg = rng.range(30.0, 70.0) as f32;
        s.weights.risk = rng.range(0.5, 5.0) as f32;
        s.weights.control = rng.range(0.5, 6.0) as f32;
    }
    let (tx, ty, tz) = (
        if plane { 0.0 } else { rng.range(-25.0, 25.0) },
        rng.range(-30.0, 30.0),
        rng.range(60.0, 110.0),
    );
    s.target.position = [tx as f32, ty as f32, tz as f32];
    s.obstacles.clear();
    let count = rng.int(3, 8);
    while s.obstacles.len() < count {
        let t = rng.range(0.15, 0.85);
        let r = rng.range(4.0, 13.0);
        let c = [
            if plane {
                0.0
            } else {
                t * tx + rng.range(-30.0, 30.0)
            },
            t * ty + rng.range(-35.0, 35.0),
            t * tz + rng.range(-10.0, 10.0),
        ];
        let far = |p: [f32; 3]| {
            let d = (0..3)
                .map(|i| (c[i] - f64::from(p[i])).powi(2))
                .sum::<f64>();
            d.sqrt() > r + MARGIN
        };
        if far(s.entry.position) && far(s.target.position) {
            // Capacity (32) exceeds 8.
            let _ = s.obstacles.push(Obstacle {
                center: [c[0] as f32, c[1] as f32, c[2] as f32],
                radius: r as f32,
            });
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenarios_are_valid_and_repeatable() {
        for seed in 0..50 {
            for plane in [true, false] {
                let s = random_scenario(seed, plane);
                assert_eq!(s.validate(), Ok(()), "seed {seed}");
                assert!((3..=8).contains(&s.obstacles.len()));
                assert_eq!(s, random_scenario(seed, plane));
                if plane {
                    assert!(s.obstacles.iter().all(|o| o.center[0] == 0.0));
                }
            }
        }
    }
}
