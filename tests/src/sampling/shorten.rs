//! The shortening pass: a found path's parameters (insertion angles, the first segments' lengths
//! and rolls) searched locally for a shorter path, its end re-solved by the exact goal connection
//! at every step, so that each candidate ends on the target and is checked against every limit.
//!
//! A compass search (each parameter up and down by its step, then a few random directions,
//! halving the steps when nothing shortens the path): derivative-free because the clearance
//! limits make the length non-smooth, and tried for every split of the path into the searched
//! segments and the re-solved connection.

use super::connect::connect;
use super::limits::Limits;
use super::route::{measure, normalize, tail_of};
use super::SampledSegment;
use needle_sim::random::{seeded, Draw};
use planner_core::SegmentKind;

/// First step of an angle (radians) and of a length (mm).
const ANGLE_STEP: f64 = 0.05;
const LENGTH_STEP: f64 = 4.0;
/// The search stops when the steps have shrunk by this factor.
const SMALLEST_STEP: f64 = 1e-7;
/// Random directions tried before the steps are halved.
const RANDOM_PROBES: usize = 6;

/// A path: insertion angles (radians) and segments.
#[derive(Clone, Debug, PartialEq)]
pub struct Route {
    /// Insertion angle about b1.
    pub theta1: f64,
    /// Insertion angle about b2.
    pub theta2: f64,
    /// Normalized segments, entry first.
    pub segments: Vec<SampledSegment>,
    /// Total length (mm).
    pub length: f64,
}

/// Which numbers of a route the search moves.
struct Layout {
    /// The segments kept before the connection (their kinds).
    kinds: Vec<SegmentKind>,
    /// Insertion angles searched: none (the cone is a line), theta1 (plane) or both.
    angles: usize,
    /// Rolls are searched (3-D).
    rolls: bool,
    /// The plane mode's fixed rolls.
    fixed_rolls: Vec<f64>,
}

impl Layout {
    fn start(&self, route: &Route) -> Vec<f64> {
        let mut x = Vec::new();
        x.extend([route.theta1, route.theta2].iter().take(self.angles));
        for s in &route.segments[..self.kinds.len()] {
            x.push(s.length);
            if self.rolls {
                x.push(s.roll);
            }
        }
        x
    }

    fn steps(&self) -> Vec<f64> {
        let mut s = Vec::new();
        s.extend([ANGLE_STEP, ANGLE_STEP].iter().take(self.angles));
        let per_segment: &[f64] = if self.rolls {
            &[LENGTH_STEP, ANGLE_STEP]
        } else {
            &[LENGTH_STEP]
        };
        for _ in &self.kinds {
            s.extend_from_slice(per_segment);
        }
        s
    }

    /// The route with parameters `x`, its end re-solved, if it keeps every limit.
    fn route(&self, l: &Limits, x: &[f64]) -> Option<Route> {
        let theta1 = if self.angles > 0 { x[0] } else { 0.0 };
        let theta2 = if self.angles > 1 { x[1] } else { 0.0 };
        let mut k = self.angles;
        let mut prefix = Vec::with_capacity(self.kinds.len() + 2);
        for (i, &kind) in self.kinds.iter().enumerate() {
            let length = x[k];
            let roll = if self.rolls {
                x[k + 1]
            } else {
                self.fixed_rolls[i]
            };
            k += if self.rolls { 2 } else { 1 };
            if !(0.0..=l.bound(kind)).contains(&length) {
                return None;
            }
            prefix.push(SampledSegment { kind, roll, length });
        }
        let prefix = normalize(&prefix);
        let head = measure(l, theta1, theta2, &prefix)?;
        let c = connect(l, &head.end, tail_of(&prefix))?;
        let segments = normalize(&[prefix, c.pieces].concat());
        let whole = measure(l, theta1, theta2, &segments)?;
        Some(Route {
            theta1,
            theta2,
            segments,
            length: whole.length,
        })
    }
}

/// The shortest route the search finds from `route`, over every split, within `evaluations`
/// route evaluations per split; `route` itself when nothing shorter is found.
pub fn shorten(l: &Limits, route: Route, evaluations: usize, seed: u64) -> Route {
    let mut best = route.clone();
    for keep in 0..route.segments.len() {
        let layout = Layout {
            kinds: route.segments[..keep].iter().map(|s| s.kind).collect(),
            angles: match (l.max_tilt > 0.0, l.plane) {
                (false, _) => 0,
                (true, true) => 1,
                (true, false) => 2,
            },
            rolls: !l.plane,
            fixed_rolls: route.segments[..keep].iter().map(|s| s.roll).collect(),
        };
        let x = layout.start(&route);
        // A split whose connection does not rebuild a valid path is no place to start from.
        let Some(start) = layout.route(l, &x) else {
            continue;
        };
        let found = search(l, &layout, x, start, evaluations, seed ^ keep as u64);
        if found.length < best.length {
            best = found;
        }
    }
    best
}

fn search(
    l: &Limits,
    layout: &Layout,
    mut x: Vec<f64>,
    mut best: Route,
    evaluations: usize,
    seed: u64,
) -> Route {
    let mut rng = seeded(seed);
    let mut steps = layout.steps();
    let mut scale = 1.0;
    let mut spent = 0;
    while scale > SMALLEST_STEP && spent < evaluations {
        let mut moves: Vec<Vec<f64>> = Vec::new();
        for i in 0..x.len() {
            for sign in [1.0, -1.0] {
                let mut m = vec![0.0; x.len()];
                m[i] = sign * steps[i];
                moves.push(m);
            }
        }
        for _ in 0..RANDOM_PROBES {
            moves.push(steps.iter().map(|s| s * rng.range(-1.0, 1.0)).collect());
        }
        let mut improved = false;
        for m in moves {
            spent += 1;
            let y: Vec<f64> = x.iter().zip(&m).map(|(a, b)| a + b).collect();
            if let Some(r) = layout.route(l, &y) {
                if r.length < best.length {
                    best = r;
                    x = y;
                    improved = true;
                    break;
                }
            }
        }
        if !improved {
            scale *= 0.5;
            steps.iter_mut().for_each(|s| *s *= 0.5);
        }
    }
    best
}
