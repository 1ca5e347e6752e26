//! The RRT baseline the paper compares against: a tree of needle motions grown from the entry
//! towards random samples (with a goal bias), each edge one step of a primitive the needle can
//! drive (a line, or an arc of the needle's curvature bent to one of a few bevel directions: both
//! sides of the plane in plane mode), until a node can reach the target within the tolerance.
//!
//! Its path is scored with the optimiser's objective (see [`super::pieces::score`]), with the
//! control degree N counted as the number of pieces after merging consecutive steps that need no
//! bevel change.

// A host-only baseline whose trees are compared as they are: it keeps libm's atan2f bits (the
// clippy.toml ban of libm trigonometry is for code the device runs).
#![allow(clippy::disallowed_methods)]

use super::pieces::{merge, score, v3, Piece, Score, Segment};
use needle_sim::random::{seeded, Draw};
use planner_core::model::clearance::closest;
use planner_core::model::kinematics::{entry_basis, insertion_frame, Frame, V3};
use planner_core::model::scenario::Workspace;
use planner_core::{PlanError, Scenario, SegmentKind};
use std::time::Instant;

/// Settings of one RRT run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Length of one tree edge (mm); the paper uses 10.
    pub step: f32,
    /// The run stops once the tip passes this close to the target (mm); the paper uses 1.
    pub tolerance: f32,
    /// Seed of the random samples.
    pub seed: u64,
    /// Most samples drawn before giving up.
    pub iterations: usize,
    /// Share of samples that are the target itself.
    pub goal_bias: f64,
    /// Bevel directions an arc may take in 3-D (plane mode always has two).
    pub rolls_3d: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            step: 10.0,
            tolerance: 1.0,
            seed: 1,
            iterations: 20_000,
            goal_bias: 0.2,
            rolls_3d: 6,
        }
    }
}

/// Why a run found no path.
#[derive(Clone, Debug, PartialEq)]
pub enum RrtError {
    /// The scenario is invalid.
    Scenario(PlanError),
    /// An option is out of range.
    Options(&'static str),
    /// The sample budget ran out; `nearest` is how close the tree came to the target (mm).
    NotFound {
        /// Samples drawn.
        iterations: usize,
        /// Nodes in the tree.
        nodes: usize,
        /// Closest approach of any node to the target (mm).
        nearest: f32,
    },
}

impl std::fmt::Display for RrtError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RrtError::Scenario(e) => write!(f, "{e}"),
            RrtError::Options(m) => f.write_str(m),
            RrtError::NotFound {
                iterations,
                nodes,
                nearest,
            } => write!(
                f,
                "no path within the tolerance after {iterations} samples ({nodes} nodes, nearest \
                 {nearest:.2} mm from the target): raise --iterations or try another --seed"
            ),
        }
    }
}

impl std::error::Error for RrtError {}

/// A node of the tree: the tip's frame after driving `piece` from `parent`.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    /// Tip frame.
    pub frame: Frame,
    /// Index of the parent (the root is its own parent).
    pub parent: usize,
    /// The piece from the parent's frame to this one.
    pub piece: Piece,
    /// Primitives already grown from this node (bit per primitive), so none is added twice.
    tried: u32,
}

/// A found path and the tree that found it.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The insertion frame (the nominal axis: the RRT does not tilt the insertion).
    pub first: Frame,
    /// Pieces from the entry to the end.
    pub pieces: Vec<Piece>,
    /// The pieces merged into segments.
    pub segments: Vec<Segment>,
    /// The objective's terms.
    pub score: Score,
    /// Every node grown (for plots).
    pub tree: Vec<Node>,
    /// Samples drawn.
    pub iterations: usize,
    /// Wall-clock time of the run (µs).
    pub time_us: u64,
}

struct Grower<'a> {
    scenario: &'a Scenario,
    radius: f32,
    floor: f32,
    primitives: Vec<(SegmentKind, f32)>,
    plane: bool,
}

impl Grower<'_> {
    fn free(&self, start: &Frame, kind: SegmentKind, length: f32) -> bool {
        self.scenario.obstacles.iter().all(|ob| {
            closest(start, kind, length, self.radius, &v3(ob.center)).distance - ob.radius
                > self.floor
        })
    }

    /// The best piece from `f` that ends within `tolerance` of the target, if any.
    fn reach(&self, f: &Frame, step: f32, tolerance: f32, target: &V3) -> Option<(Piece, f32)> {
        let rel = target - f.p;
        let (a, b) = (rel.dot(&f.e1()), rel.dot(&f.e2()));
        // The roll that puts the target in the bending plane, on the bevel's side.
        let roll = if self.plane {
            if b >= 0.0 {
                0.0
            } else {
                core::f32::consts::PI
            }
        } else {
            libm::atan2f(-a, b)
        };
        let mut best: Option<(Piece, f32)> = None;
        for (kind, roll) in [(SegmentKind::Line, 0.0), (SegmentKind::Arc, roll)] {
            let start = f.rolled(roll);
            let c = closest(&start, kind, step, self.radius, target);
            if c.distance <= tolerance
                && c.at > 0.0
                && best.is_none_or(|(_, d)| c.distance < d)
                && self.free(&start, kind, c.at)
            {
                best = Some((
                    Piece {
                        kind,
                        roll,
                        length: c.at,
                    },
                    c.distance,
                ));
            }
        }
        best
    }

    /// One sample: the target with probability `goal_bias`, else a point of the box `lo`..`hi`
    /// (in the entry's plane in plane mode).
    fn sample(&self, rng: &mut impl Draw, goal_bias: f64, target: V3, (lo, hi): (V3, V3)) -> V3 {
        if rng.unit() < goal_bias {
            return target;
        }
        let mut s = V3::zeros();
        for k in 0..3 {
            s[k] = rng.range(f64::from(lo[k]), f64::from(hi[k])) as f32;
        }
        if self.plane {
            s.x = self.scenario.entry.position[0];
        }
        s
    }

    /// Grows node `near` by the untried primitive that ends closest to `sample`, marking it
    /// tried; the new node's frame, or `None` when that primitive hits an obstacle.
    fn grow(&self, tree: &mut Vec<Node>, near: usize, sample: V3, step: f32) -> Option<Frame> {
        let from = tree[near].frame;
        let mut options_here: Vec<(usize, Frame, f32)> = self
            .primitives
            .iter()
            .enumerate()
            .filter(|(k, _)| tree[near].tried & (1 << k) == 0)
            .map(|(k, &(kind, roll))| {
                let start = from.rolled(roll);
                let end = start.advanced(kind, step, self.radius);
                (k, start, (end.p - sample).norm())
            })
            .collect();
        options_here.sort_by(|a, b| a.2.total_cmp(&b.2));
        let &(k, start, _) = options_here.first()?;
        tree[near].tried |= 1 << k;
        let (kind, roll) = self.primitives[k];
        if !self.free(&start, kind, step) {
            return None;
        }
        let frame = start.advanced(kind, step, self.radius);
        tree.push(Node {
            frame,
            parent: near,
            piece: Piece {
                kind,
                roll,
                length: step,
            },
            tried: 0,
        });
        Some(frame)
    }
}

/// The node nearest to `sample` with a primitive left to grow, if any.
fn nearest_open(tree: &[Node], primitives: usize, sample: V3) -> Option<usize> {
    tree.iter()
        .enumerate()
        .filter(|(_, n)| n.tried.count_ones() < primitives as u32)
        .map(|(i, n)| (i, (n.frame.p - sample).norm_squared()))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// The pieces from the root to `leaf`, then `last`.
fn path_to(tree: &[Node], leaf: usize, last: Piece) -> Vec<Piece> {
    let mut pieces = vec![last];
    let mut at = leaf;
    while at != 0 {
        pieces.push(tree[at].piece);
        at = tree[at].parent;
    }
    pieces.reverse();
    pieces
}

/// The primitives a node may grow: a line, and an arc at each bevel roll (the plane's two sides
/// in plane mode, `rolls_3d` evenly spaced rolls in (-π, π] in 3-D).
fn primitives(plane: bool, rolls_3d: usize) -> Vec<(SegmentKind, f32)> {
    let rolls: Vec<f32> = if plane {
        vec![0.0, core::f32::consts::PI]
    } else {
        let m = rolls_3d.clamp(2, 30);
        (0..m)
            .map(|k| core::f32::consts::TAU * k as f32 / m as f32)
            .map(|r| {
                if r > core::f32::consts::PI {
                    r - core::f32::consts::TAU
                } else {
                    r
                }
            })
            .collect()
    };
    let mut primitives = vec![(SegmentKind::Line, 0.0)];
    primitives.extend(rolls.iter().map(|&r| (SegmentKind::Arc, r)));
    primitives
}

fn check(options: &Options) -> Result<(), RrtError> {
    if !(options.step > 0.0 && options.step.is_finite()) {
        return Err(RrtError::Options("--step must be a positive number"));
    }
    if !(options.tolerance > 0.0 && options.tolerance.is_finite()) {
        return Err(RrtError::Options("--tolerance must be a positive number"));
    }
    if options.iterations == 0 {
        return Err(RrtError::Options("--iterations must be at least 1"));
    }
    if !(0.0..=1.0).contains(&options.goal_bias) {
        return Err(RrtError::Options("the goal bias must lie in [0, 1]"));
    }
    Ok(())
}

fn bounds(scenario: &Scenario, margin: f32) -> (V3, V3) {
    let mut lo = v3(scenario.entry.position);
    let mut hi = lo;
    let mut grow = |c: V3, r: f32| {
        for k in 0..3 {
            lo[k] = lo[k].min(c[k] - r);
            hi[k] = hi[k].max(c[k] + r);
        }
    };
    grow(v3(scenario.target.position), 0.0);
    for ob in &scenario.obstacles {
        grow(v3(ob.center), ob.radius);
    }
    (lo.add_scalar(-margin), hi.add_scalar(margin))
}

/// Grows a tree until the target is reached within `options.tolerance`.
pub fn run(scenario: &Scenario, options: &Options) -> Result<Outcome, RrtError> {
    let clock = Instant::now();
    scenario.validate().map_err(RrtError::Scenario)?;
    check(options)?;
    let plane = scenario.options.workspace == Workspace::PlaneYz;
    let grower = Grower {
        scenario,
        radius: scenario.needle.curvature_radius,
        floor: scenario.options.min_clearance,
        primitives: primitives(plane, options.rolls_3d),
        plane,
    };
    let e = &scenario.entry;
    let first = insertion_frame(v3(e.position), &entry_basis(e.direction), 0.0, 0.0);
    let target = v3(scenario.target.position);
    let sample_box = bounds(scenario, 2.0 * options.step);
    let mut rng = seeded(options.seed);
    let mut tree = vec![Node {
        frame: first,
        parent: 0,
        piece: Piece {
            kind: SegmentKind::Line,
            roll: 0.0,
            length: 0.0,
        },
        tried: 0,
    }];
    let mut nearest = (first.p - target).norm();
    let finish = |tree: Vec<Node>, leaf: usize, last: Piece, iterations: usize| {
        let pieces = path_to(&tree, leaf, last);
        Outcome {
            first,
            segments: merge(&pieces),
            score: score(scenario, &first, &pieces),
            pieces,
            tree,
            iterations,
            time_us: clock.elapsed().as_micros() as u64,
        }
    };
    if let Some((piece, _)) = grower.reach(&first, options.step, options.tolerance, &target) {
        return Ok(finish(tree, 0, piece, 0));
    }
    for it in 1..=options.iterations {
        let sample = grower.sample(&mut rng, options.goal_bias, target, sample_box);
        let Some(near) = nearest_open(&tree, grower.primitives.len(), sample) else {
            break; // every node has grown every primitive
        };
        let Some(frame) = grower.grow(&mut tree, near, sample, options.step) else {
            continue;
        };
        nearest = nearest.min((frame.p - target).norm());
        let leaf = tree.len() - 1;
        if let Some((piece, _)) = grower.reach(&frame, options.step, options.tolerance, &target) {
            return Ok(finish(tree, leaf, piece, it));
        }
    }
    Err(RrtError::NotFound {
        iterations: options.iterations,
        nodes: tree.len(),
        nearest,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pieces::path_points;

    #[test]
    fn free_space_run_reaches_within_tolerance_and_is_deterministic() {
        let mut s = Scenario::paper();
        s.obstacles.clear();
        let o = Options {
            seed: 3,
            ..Options::default()
        };
        let a = run(&s, &o).expect("a path in free space");
        assert!(a.score.target_error <= 1.0);
        assert!(a.score.risk == 0.0 && a.score.penalty == 0.0);
        let b = run(&s, &o).expect("same again");
        assert_eq!(a.pieces, b.pieces);
        let pts = path_points(&a.first, &a.pieces, s.needle.curvature_radius, 1.0);
        let end = pts.last().copied().unwrap_or_default();
        let t = s.target.position;
        let err =
            ((end[0] - t[0]).powi(2) + (end[1] - t[1]).powi(2) + (end[2] - t[2]).powi(2)).sqrt();
        assert!((err - a.score.target_error).abs() < 1e-3);
    }

    #[test]
    fn options_are_checked() {
        let s = Scenario::paper();
        for bad in [
            Options {
                step: 0.0,
                ..Options::default()
            },
            Options {
                tolerance: -1.0,
                ..Options::default()
            },
            Options {
                iterations: 0,
                ..Options::default()
            },
        ] {
            assert!(matches!(run(&s, &bad), Err(RrtError::Options(_))));
        }
    }
}
