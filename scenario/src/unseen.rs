//! Seeded 3-D scenarios the planner was never tuned on, for `needle benchmark`.
//!
//! [`unseen_scenario`]`(seed)` starts from [`Scenario::paper`] (its needle, entry at the origin
//! heading +z, weights, bounds and N) in the space workspace, and draws:
//! - the target [`TARGET_DISTANCE_MM`] from the entry, in a direction at most
//!   [`TARGET_OFF_AXIS_DEG`] off the entry's axis (uniform over that cap), well inside the
//!   entry's tilt cone, so some posture can reach it;
//! - [`SPHERES`] spheres of radius [`RADIUS_MM`]: the first blocks the straight entry–target
//!   line (its centre at most 0.8 of its radius off the line, between [`BLOCKING_SPAN`] of the
//!   way along it), the others scattered around the corridor (anywhere from
//!   [`SCATTER_ALONG`] of the way, at most [`SCATTER_OFF_AXIS_MM`] off the line);
//! - every sphere clear of the entry and of the target by at least [`CLEARANCE_MM`] (a sphere
//!   drawn closer is drawn again).
//!
//! Spheres may overlap one another, as tissue does. A scenario is a function of its seed alone
//! (the project's one generator, `needle_sim::random`), on every machine. It is not the family
//! the optimality tests draw (`tests/src/reference/random.rs`), on which the planner was tuned.

use needle_sim::random::{seeded, Draw};
use planner_core::model::scenario::{Obstacle, Workspace};
use planner_core::Scenario;

/// Distance of the target from the entry (mm), least and most.
pub const TARGET_DISTANCE_MM: (f64, f64) = (60.0, 100.0);
/// Largest angle between the entry's axis and the direction to the target (degrees).
pub const TARGET_OFF_AXIS_DEG: f64 = 25.0;
/// Number of spheres, least and most (both included).
pub const SPHERES: (usize, usize) = (3, 16);
/// Sphere radius (mm), least and most.
pub const RADIUS_MM: (f64, f64) = (3.0, 12.0);
/// Where along the entry–target line the blocking sphere's centre lies (fractions of the way).
pub const BLOCKING_SPAN: (f64, f64) = (0.25, 0.75);
/// Where along the line the other spheres' centres lie (fractions of the way).
pub const SCATTER_ALONG: (f64, f64) = (0.1, 0.9);
/// Largest distance of the other spheres' centres from the line (mm).
pub const SCATTER_OFF_AXIS_MM: f64 = 35.0;
/// Least distance between any sphere's surface and the entry or the target (mm).
pub const CLEARANCE_MM: f64 = 3.0;

/// Keeps these scenarios' draws apart from every other family seeded from the same numbers.
const FAMILY: u64 = 0x756E_7365_656E_3364;

pub(super) type V3 = [f64; 3];

pub(super) fn add(a: V3, b: V3, k: f64) -> V3 {
    [a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2]]
}

pub(super) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(super) fn norm(a: V3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

pub(super) fn unit(a: V3) -> V3 {
    let n = norm(a);
    [a[0] / n, a[1] / n, a[2] / n]
}

pub(super) fn distance(a: V3, b: V3) -> f64 {
    norm(add(a, b, -1.0))
}

/// The generated scenario of `seed` (any value): valid, and the same on every call.
pub fn unseen_scenario(seed: u64) -> Scenario {
    let mut rng = seeded(seed ^ FAMILY);
    let mut s = Scenario::paper();
    s.options.workspace = Workspace::Space;
    s.obstacles.clear();
    let entry = s.entry.position.map(f64::from);
    let cos_cap = TARGET_OFF_AXIS_DEG.to_radians().cos();
    let cos_off = rng.range(cos_cap, 1.0);
    let sin_off = (1.0 - cos_off * cos_off).sqrt();
    let around = rng.range(0.0, std::f64::consts::TAU);
    let axis = [sin_off * around.cos(), sin_off * around.sin(), cos_off];
    let length = rng.range(TARGET_DISTANCE_MM.0, TARGET_DISTANCE_MM.1);
    let target = add(entry, axis, length);
    s.target.position = target.map(|v| v as f32);
    draw_spheres(&mut rng, &mut s, axis, length, usize::MAX, |_, _| true);
    s
}

/// Draws the spheres of a scenario whose entry and target are set (the target `length` mm along
/// the unit `axis` from the entry), as the module describes; a sphere `keep(centre, radius)`
/// refuses is drawn again. False when `max_draws` draws did not give them all.
pub(super) fn draw_spheres(
    rng: &mut impl Draw,
    s: &mut Scenario,
    axis: V3,
    length: f64,
    max_draws: usize,
    keep: impl Fn(V3, f64) -> bool,
) -> bool {
    let entry = s.entry.position.map(f64::from);
    let target = add(entry, axis, length);
    // Two directions across the line, to place centres off it.
    let across = unit(cross(axis, [1.0, 0.0, 0.0]));
    let across2 = cross(axis, across);
    let count = rng.int(SPHERES.0, SPHERES.1);
    let mut draws = 0usize;
    while s.obstacles.len() < count {
        if draws == max_draws {
            return false;
        }
        draws += 1;
        let blocking = s.obstacles.is_empty();
        let radius = rng.range(RADIUS_MM.0, RADIUS_MM.1);
        let (span, off) = if blocking {
            (BLOCKING_SPAN, rng.range(0.0, 0.8 * radius))
        } else {
            (SCATTER_ALONG, rng.range(0.0, SCATTER_OFF_AXIS_MM))
        };
        let along = rng.range(span.0, span.1) * length;
        let turn = rng.range(0.0, std::f64::consts::TAU);
        let centre = add(
            add(add(entry, axis, along), across, off * turn.cos()),
            across2,
            off * turn.sin(),
        );
        let clear = |p: V3| distance(centre, p) - radius >= CLEARANCE_MM;
        if clear(entry) && clear(target) && keep(centre, radius) {
            // At most 16 spheres: within the capacity (32).
            let _ = s.obstacles.push(Obstacle {
                center: centre.map(|v| v as f32),
                radius: radius as f32,
            });
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f64s(p: [f32; 3]) -> V3 {
        p.map(f64::from)
    }

    /// Where along the entry–target line a point projects (fraction of the way), and its
    /// distance from the line.
    fn along_and_off(s: &Scenario, p: V3) -> (f64, f64) {
        let (e, t) = (f64s(s.entry.position), f64s(s.target.position));
        let line = add(t, e, -1.0);
        let rel = add(p, e, -1.0);
        let len = norm(line);
        let along = (rel[0] * line[0] + rel[1] * line[1] + rel[2] * line[2]) / len;
        (along / len, distance(p, add(e, unit(line), along)))
    }

    #[test]
    fn scenarios_are_valid_repeatable_and_as_documented() {
        let cap = TARGET_OFF_AXIS_DEG.to_radians().cos();
        for seed in 0..300 {
            let s = unseen_scenario(seed);
            assert_eq!(s.validate(), Ok(()), "seed {seed}");
            assert_eq!(s, unseen_scenario(seed), "seed {seed}");
            assert_eq!(s.options.workspace, Workspace::Space);
            let paper = Scenario::paper();
            assert_eq!(
                (s.needle, s.entry, s.weights, s.driver),
                (paper.needle, paper.entry, paper.weights, paper.driver)
            );
            let n = s.obstacles.len();
            assert!((SPHERES.0..=SPHERES.1).contains(&n), "seed {seed}: {n}");
            let (e, t) = (f64s(s.entry.position), f64s(s.target.position));
            let d = distance(e, t);
            let slack = 1e-4;
            assert!(d >= TARGET_DISTANCE_MM.0 - slack && d <= TARGET_DISTANCE_MM.1 + slack);
            assert!(
                (t[2] - e[2]) / d >= cap - 1e-6,
                "seed {seed}: target off the cone"
            );
            let b = &s.obstacles[0];
            let (along, off) = along_and_off(&s, f64s(b.center));
            assert!(
                off < f64::from(b.radius),
                "seed {seed}: the first does not block"
            );
            let (lo, hi) = BLOCKING_SPAN;
            assert!(
                along >= lo - 1e-5 && along <= hi + 1e-5,
                "seed {seed}: {along}"
            );
            for o in &s.obstacles {
                let r = f64::from(o.radius);
                assert!(r >= RADIUS_MM.0 - slack && r <= RADIUS_MM.1 + slack);
                for p in [e, t] {
                    let gap = distance(f64s(o.center), p) - r;
                    assert!(gap >= CLEARANCE_MM - 1e-3, "seed {seed}: gap {gap}");
                }
            }
        }
    }

    #[test]
    fn seeds_give_different_scenarios() {
        let a = unseen_scenario(101);
        let b = unseen_scenario(102);
        assert_ne!(a.target.position, b.target.position);
        let counts: std::collections::BTreeSet<usize> = (0..60)
            .map(|k| unseen_scenario(k).obstacles.len())
            .collect();
        assert!(counts.contains(&SPHERES.0) && counts.contains(&SPHERES.1));
    }
}
