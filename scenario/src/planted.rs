//! Seeded 3-D scenarios with a path planted in them: `needle benchmark --generator planted`.
//!
//! The unseen generator ([`super::unseen`]) places spheres without knowing whether any path is
//! left between them, and about one scenario in six has none: a refusal there says nothing of
//! the planner. [`planted_scenario`]`(seed)` draws a needle path first and the spheres around it:
//! - **the path**: from the entry, a posture at most [`POSTURE_TILT_DEG`] off the entry's axis
//!   (uniform over that cap) with the bevel in any direction; a form drawn from R L, L R, R R and
//!   R, the bevel turned by any angle between two arcs; arcs of the radius a closed-loop plan
//!   keeps ([`CLOSED_LOOP_CURVATURE_RESERVE`] of the curvature in reserve), each turning by an
//!   angle in [`ARC_DEG`], lines of a length in [`LINE_MM`]. Drawn again until its end lies where
//!   the unseen generator puts a target (60–100 mm from the entry, at most 25° off its axis);
//!   the end is the target;
//! - **the spheres** as the unseen generator draws them (as many, as large, the first blocking
//!   the straight entry–target line, the others scattered around it, clear of the entry and the
//!   target), each also at least [`PATH_CLEARANCE_MM`] from the planted path (drawn again if
//!   not). Where the first sphere cannot block the line without coming that near the path (a
//!   path that hugs the line), the path is drawn again.
//!
//! So every scenario has a path with that clearance which the steering's curvature reserve can
//! follow: a scenario refused, or a run that fails, is the planner's or the controller's doing,
//! not the generator's. The planted path itself is not in the scenario.

use super::execution::CLOSED_LOOP_CURVATURE_RESERVE;
use super::unseen::{
    add, cross, distance, draw_spheres, norm, unit, TARGET_DISTANCE_MM, TARGET_OFF_AXIS_DEG, V3,
};
use needle_sim::random::{seeded, Draw};
use planner_core::model::scenario::Workspace;
use planner_core::Scenario;

/// Largest angle between the planted path's posture and the entry's axis (degrees).
pub const POSTURE_TILT_DEG: f64 = 20.0;
/// The angle each planted arc turns by (degrees), least and most.
pub const ARC_DEG: (f64, f64) = (15.0, 75.0);
/// The length of a planted line (mm), least and most.
pub const LINE_MM: (f64, f64) = (10.0, 90.0);
/// Least distance between any sphere's surface and the planted path (mm).
pub const PATH_CLEARANCE_MM: f64 = 2.0;
/// Sphere draws allowed for one path before the path is drawn again.
const MAX_SPHERE_DRAWS: usize = 2000;
/// Spacing of the points at which the path's clearance is measured (mm).
const SAMPLE_MM: f64 = 0.5;

/// Keeps these scenarios' draws apart from every other family seeded from the same numbers.
const FAMILY: u64 = 0x706C_616E_7465_6421;

/// The tip while the planted path is drawn: position, heading and bevel direction (unit,
/// orthogonal).
struct Tip {
    p: V3,
    heading: V3,
    bevel: V3,
}

impl Tip {
    /// Pushes `length` mm, bending towards the bevel on a circle of `radius` (a line without),
    /// recording a point every [`SAMPLE_MM`].
    fn push(&mut self, length: f64, radius: Option<f64>, points: &mut Vec<V3>) {
        let pieces = (length / SAMPLE_MM).ceil().max(1.0) as usize;
        let (p0, h0, b0) = (self.p, self.heading, self.bevel);
        for k in 1..=pieces {
            let s = length * k as f64 / pieces as f64;
            match radius {
                Some(r) => {
                    let (sn, cs) = (s / r).sin_cos();
                    self.p = add(add(p0, h0, r * sn), b0, r * (1.0 - cs));
                    self.heading = add(h0.map(|v| v * cs), b0, sn);
                    self.bevel = add(b0.map(|v| v * cs), h0, -sn);
                }
                None => self.p = add(p0, h0, s),
            }
            points.push(self.p);
        }
    }

    /// Turns the bevel by `angle` (radians) about the heading.
    fn turn(&mut self, angle: f64) {
        let side = cross(self.heading, self.bevel);
        self.bevel = add(self.bevel.map(|v| v * angle.cos()), side, angle.sin());
    }
}

/// A needle path drawn as the module describes, from `entry` about `axis`: its points (the
/// entry first, the end last).
fn draw_path(rng: &mut impl Draw, entry: V3, axis: V3, radius: f64) -> Vec<V3> {
    let across = unit(cross(axis, [1.0, 0.0, 0.0]));
    let across2 = cross(axis, across);
    let cos_tilt = rng.range(POSTURE_TILT_DEG.to_radians().cos(), 1.0);
    let sin_tilt = (1.0 - cos_tilt * cos_tilt).sqrt();
    let around = rng.range(0.0, std::f64::consts::TAU);
    let tilted = add(
        add(axis.map(|v| v * cos_tilt), across, sin_tilt * around.cos()),
        across2,
        sin_tilt * around.sin(),
    );
    let heading = unit(tilted);
    let side = unit(cross(heading, across));
    let mut tip = Tip {
        p: entry,
        heading,
        bevel: unit(cross(side, heading)),
    };
    tip.turn(rng.range(0.0, std::f64::consts::TAU));
    let arc =
        |rng: &mut dyn FnMut(f64, f64) -> f64| radius * rng(ARC_DEG.0, ARC_DEG.1).to_radians();
    let line = |rng: &mut dyn FnMut(f64, f64) -> f64| rng(LINE_MM.0, LINE_MM.1);
    let mut draw = |lo: f64, hi: f64| rng.range(lo, hi);
    let mut points = vec![entry];
    // R L, L R, R R or R, one chance in four each.
    match draw(0.0, 4.0) as u32 {
        0 => {
            tip.push(arc(&mut draw), Some(radius), &mut points);
            tip.push(line(&mut draw), None, &mut points);
        }
        1 => {
            tip.push(line(&mut draw), None, &mut points);
            tip.push(arc(&mut draw), Some(radius), &mut points);
        }
        2 => {
            tip.push(arc(&mut draw), Some(radius), &mut points);
            tip.turn(draw(0.0, std::f64::consts::TAU));
            tip.push(arc(&mut draw), Some(radius), &mut points);
        }
        _ => tip.push(arc(&mut draw), Some(radius), &mut points),
    }
    points
}

/// Where the unseen generator may put a target: its distance from the entry and its angle off
/// the entry's axis within bounds.
fn target_in_bounds(entry: V3, axis: V3, end: V3) -> bool {
    let to = add(end, entry, -1.0);
    let d = norm(to);
    let cos_off = (to[0] * axis[0] + to[1] * axis[1] + to[2] * axis[2]) / d;
    d >= TARGET_DISTANCE_MM.0
        && d <= TARGET_DISTANCE_MM.1
        && cos_off >= TARGET_OFF_AXIS_DEG.to_radians().cos()
}

/// The smallest distance between a sphere's surface and the path's points.
fn path_gap(points: &[V3], centre: V3, radius: f64) -> f64 {
    points
        .iter()
        .map(|&p| distance(p, centre))
        .fold(f64::INFINITY, f64::min)
        - radius
}

/// The planted scenario of `seed` (any value): valid, and the same on every call.
pub fn planted_scenario(seed: u64) -> Scenario {
    planted_with_path(seed).0
}

/// [`planted_scenario`] and the points of the path planted in it.
pub fn planted_with_path(seed: u64) -> (Scenario, Vec<V3>) {
    let mut rng = seeded(seed ^ FAMILY);
    let mut base = Scenario::paper();
    base.options.workspace = Workspace::Space;
    base.obstacles.clear();
    let entry = base.entry.position.map(f64::from);
    let axis = unit(base.entry.direction.map(f64::from));
    let radius =
        f64::from(base.needle.curvature_radius) / (1.0 - f64::from(CLOSED_LOOP_CURVATURE_RESERVE));
    loop {
        let points = draw_path(&mut rng, entry, axis, radius);
        let Some(&end) = points.last() else { continue };
        if !target_in_bounds(entry, axis, end) {
            continue;
        }
        let length = distance(end, entry);
        let line = unit(add(end, entry, -1.0));
        let mut s = base.clone();
        s.target.position = add(entry, line, length).map(|v| v as f32);
        let clear = |centre: V3, r: f64| path_gap(&points, centre, r) >= PATH_CLEARANCE_MM;
        if draw_spheres(&mut rng, &mut s, line, length, MAX_SPHERE_DRAWS, clear) {
            return (s, points);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unseen::{CLEARANCE_MM, RADIUS_MM, SPHERES};

    fn f64s(p: [f32; 3]) -> V3 {
        p.map(f64::from)
    }

    #[test]
    fn every_scenario_keeps_its_planted_path_clear() {
        for seed in 0..200 {
            let (s, path) = planted_with_path(seed);
            assert_eq!(s.validate(), Ok(()), "seed {seed}");
            assert_eq!(s, planted_scenario(seed), "seed {seed}");
            let (e, t) = (f64s(s.entry.position), f64s(s.target.position));
            assert!(distance(path[0], e) < 1e-9);
            assert!(
                distance(path[path.len() - 1], t) < 1e-4,
                "seed {seed}: ends off"
            );
            assert!(target_in_bounds(e, [0.0, 0.0, 1.0], t), "seed {seed}");
            let steps: Vec<f64> = path.windows(2).map(|w| distance(w[0], w[1])).collect();
            assert!(steps.iter().all(|&d| d <= SAMPLE_MM + 1e-9), "seed {seed}");
            let length: f64 = steps.iter().sum();
            assert!(length < f64::from(s.needle.length), "seed {seed}: {length}");
            let n = s.obstacles.len();
            assert!((SPHERES.0..=SPHERES.1).contains(&n), "seed {seed}: {n}");
            for (i, o) in s.obstacles.iter().enumerate() {
                let (c, r) = (f64s(o.center), f64::from(o.radius));
                assert!(r >= RADIUS_MM.0 - 1e-4 && r <= RADIUS_MM.1 + 1e-4);
                let gap = path_gap(&path, c, r);
                assert!(
                    gap >= PATH_CLEARANCE_MM - 1e-4,
                    "seed {seed}, sphere {i}: {gap}"
                );
                for p in [e, t] {
                    assert!(distance(c, p) - r >= CLEARANCE_MM - 1e-3, "seed {seed}");
                }
            }
            // The first sphere blocks the straight line: its centre is nearer the line than
            // its radius.
            let b = &s.obstacles[0];
            let line = unit(add(t, e, -1.0));
            let rel = add(f64s(b.center), e, -1.0);
            let along = rel[0] * line[0] + rel[1] * line[1] + rel[2] * line[2];
            let off = distance(f64s(b.center), add(e, line, along));
            assert!(
                off < f64::from(b.radius),
                "seed {seed}: the first does not block"
            );
        }
    }

    /// The path bends as a needle does: away from the straight line by what its arcs turn, and
    /// the four forms all occur.
    #[test]
    fn planted_paths_are_needle_paths_of_every_form() {
        let radius = 63.7 / (1.0 - f64::from(CLOSED_LOOP_CURVATURE_RESERVE));
        let mut curved_lengths = Vec::new();
        for seed in 0..200 {
            let (_, path) = planted_with_path(seed);
            // Curvature from three points 2 mm apart: 1/radius on an arc, 0 on a line.
            let mut arc_mm = 0.0;
            for w in path.windows(5).step_by(4) {
                let (a, b, c) = (w[0], w[2], w[4]);
                let area2 = norm(cross(add(b, a, -1.0), add(c, a, -1.0)));
                let k = 2.0 * area2 / (distance(a, b) * distance(b, c) * distance(a, c));
                assert!(
                    k < 1.0 / radius + 1e-3,
                    "seed {seed}: bends at radius {}",
                    1.0 / k
                );
                if k > 0.5 / radius {
                    arc_mm += distance(a, c);
                }
            }
            curved_lengths.push((arc_mm, path.len() as f64 * SAMPLE_MM));
        }
        assert!(curved_lengths.iter().any(|&(a, l)| a > 0.9 * l), "some R");
        assert!(
            curved_lengths.iter().all(|&(a, _)| a > 10.0),
            "an arc in each"
        );
        assert!(
            curved_lengths.iter().any(|&(a, l)| a < 0.6 * l),
            "some with a line"
        );
    }
}
