//! The goal-directed RRT over tip frames: roots at the entry (one per insertion heading drawn in
//! the tilt cone), edges of 1 to 40 mm of line or of arc after a roll, and the exact goal
//! connection tried from every new node; the shortest connected path within the budget wins.

use super::connect::{connect, Connection};
use super::limits::Limits;
use super::route::Tail;
use super::SampledSegment;
use crate::reference::frame::{Frame, V3};
use core::f64::consts::PI;
use needle_sim::random::{seeded, Draw};
use planner_core::SegmentKind;

/// Shortest and longest edge (mm), drawn log-uniformly: short edges thread between spheres a
/// millimetre apart, long ones reach round the far side of a cluster in few nodes.
const SHORTEST_STEP: f64 = 1.0;
const LONGEST_STEP: f64 = 40.0;
/// Share of samples drawn from the wide box (a needle's loop round the target reaches up to two
/// arc diameters away); the others fill the box round the entry and the target.
const WIDE_SHARE: f64 = 0.2;
/// Share of samples that are the target itself.
const GOAL_BIAS: f64 = 0.1;
/// Share of edges that continue the last segment (no roll, same kind): a path has at most N
/// segments, so most edges must not start one.
const CONTINUE_SHARE: f64 = 0.5;
/// Share of new segments after an arc that are lines (the others are arcs).
const LINE_SHARE: f64 = 0.4;
/// Share of arcs rolled so that the sample lies on the bevel's side (the others roll at random).
const AIMED_ROLL_SHARE: f64 = 0.7;
/// Share of iterations that add a root with a new insertion heading (when the cone is not a line).
const NEW_ROOT_SHARE: f64 = 0.05;
/// Weight of the heading's angle to a sample against its distance, in arc radii per radian: the
/// needle reaches what lies ahead of it far more easily than what lies beside it.
const HEADING_WEIGHT: f64 = 0.5;

/// A tip frame reached from the entry.
#[derive(Clone, Debug)]
struct Node {
    frame: Frame,
    /// The node this one's edge leaves; `None` for a root.
    parent: Option<usize>,
    /// The insertion angles of the root this node grows from.
    posture: (f64, f64),
    /// The edge from the parent (empty for a root).
    edge: SampledSegment,
    tail: Tail,
    /// Path length from the entry (mm).
    cost: f64,
}

/// The best path the tree connected to the target: insertion angles and pieces.
#[derive(Clone, Debug)]
pub struct TreePath {
    /// Insertion angles (radians).
    pub posture: (f64, f64),
    /// The pieces, entry first (not yet merged into segments).
    pub pieces: Vec<SampledSegment>,
    /// Total length (mm).
    pub length: f64,
    /// Nodes the tree had grown when it stopped.
    pub nodes: usize,
}

struct Tree<'a> {
    limits: &'a Limits,
    nodes: Vec<Node>,
    best: Option<(usize, Connection, f64)>,
    /// The box round the entry and the target, and the wide one (corners).
    boxes: [(V3, V3); 2],
}

/// Grows the tree for `iterations` iterations from `seed` and returns the shortest path it
/// connected to the target.
pub fn grow(limits: &Limits, iterations: usize, seed: u64) -> Option<TreePath> {
    let mut rng = seeded(seed);
    let (e, t) = (limits.entry, limits.target);
    let lo = V3::new(e.x.min(t.x), e.y.min(t.y), e.z.min(t.z));
    let hi = V3::new(e.x.max(t.x), e.y.max(t.y), e.z.max(t.z));
    let padded = |pad: f64| (lo - V3::new(pad, pad, pad), hi + V3::new(pad, pad, pad));
    let mut tree = Tree {
        limits,
        nodes: Vec::new(),
        best: None,
        boxes: [
            padded((0.5 * (t - e).norm()).max(20.0)),
            padded(4.0 * limits.rho),
        ],
    };
    let aimed = limits.aimed_posture(t);
    tree.add_root(aimed);
    if aimed != (0.0, 0.0) {
        tree.add_root((0.0, 0.0));
    }
    for _ in 0..iterations {
        let q = tree.sample(&mut rng);
        if limits.max_tilt > 0.0 && rng.unit() < NEW_ROOT_SHARE {
            let posture = if rng.unit() < 0.5 {
                limits.aimed_posture(q)
            } else {
                limits.random_posture(&mut rng)
            };
            tree.add_root(posture);
            continue;
        }
        if let Some(from) = tree.nearest(q) {
            if let Some(node) = tree.extend(from, q, &mut rng) {
                tree.add(node);
            }
        }
    }
    tree.best_path()
}

impl Tree<'_> {
    fn sample(&self, rng: &mut impl Draw) -> V3 {
        if rng.unit() < GOAL_BIAS {
            return self.limits.target;
        }
        let (lo, hi) = self.boxes[usize::from(rng.unit() < WIDE_SHARE)];
        let x = if self.limits.plane {
            self.limits.entry.x
        } else {
            rng.range(lo.x, hi.x)
        };
        V3::new(x, rng.range(lo.y, hi.y), rng.range(lo.z, hi.z))
    }

    fn add_root(&mut self, posture: (f64, f64)) {
        self.add(Node {
            frame: self.limits.insertion(posture.0, posture.1),
            parent: None,
            posture,
            edge: SampledSegment {
                kind: SegmentKind::Line,
                roll: 0.0,
                length: 0.0,
            },
            tail: Tail::START,
            cost: 0.0,
        });
    }

    /// Adds `node` and tries the goal connection from it.
    fn add(&mut self, node: Node) {
        let connection = connect(self.limits, &node.frame, node.tail);
        let index = self.nodes.len();
        if let Some(c) = connection {
            let total = node.cost + c.length;
            if self.best.as_ref().is_none_or(|b| total < b.2) {
                self.best = Some((index, c, total));
            }
        }
        self.nodes.push(node);
    }

    /// The node that reaches `q` most easily: near, and heading towards it.
    fn nearest(&self, q: V3) -> Option<usize> {
        let l = self.limits;
        let open = |n: &Node| n.tail.count < l.max_segments || n.tail.kind.is_some();
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| open(n))
            .map(|(i, n)| {
                let v = q - n.frame.p;
                let d = v.norm();
                let angle = if d > 0.0 {
                    (v.dot(n.frame.e3) / d).clamp(-1.0, 1.0).acos()
                } else {
                    0.0
                };
                (i, d + HEADING_WEIGHT * l.rho * angle)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// One edge from node `from` towards `q`, if it keeps within the limits and clear: the last
    /// segment continued, or a new one; halved (down to a tenth, or 1 mm) while the edge would hit
    /// an obstacle.
    fn extend(&self, from: usize, q: V3, rng: &mut impl Draw) -> Option<Node> {
        let l = self.limits;
        let n = &self.nodes[from];
        let f = n.frame;
        let v = q - f.p;
        let (kind, roll) = match n.tail.kind {
            Some(kind) if n.tail.count == l.max_segments || rng.unit() < CONTINUE_SHARE => {
                (kind, 0.0)
            }
            last => {
                if last != Some(SegmentKind::Line) && rng.unit() < LINE_SHARE {
                    (SegmentKind::Line, 0.0)
                } else {
                    (SegmentKind::Arc, self.arc_roll(f, v, rng))
                }
            }
        };
        let g = l.roll(&f, roll);
        let mut len = (rng.range(SHORTEST_STEP.ln(), LONGEST_STEP.ln())).exp();
        if kind == SegmentKind::Arc {
            // Stop turning once the heading points at the sample.
            let aim = v.dot(g.e2).atan2(v.dot(g.e3));
            if aim > 0.0 {
                len = len.min(aim * l.rho);
            }
        }
        let room = if n.tail.continued_by(kind, roll) {
            l.bound(kind) - n.tail.run
        } else {
            l.bound(kind)
        };
        len = len.min(room);
        let shortest = (0.1 * len).min(SHORTEST_STEP);
        while l.clearance_of(&g, kind, len) < l.clearance {
            len *= 0.5;
            if len < shortest {
                return None;
            }
        }
        if len <= 1e-6 {
            return None;
        }
        let tail = n.tail.then(l, kind, roll, len)?;
        Some(Node {
            frame: l.advance(&g, kind, len),
            parent: Some(from),
            posture: n.posture,
            edge: SampledSegment {
                kind,
                roll,
                length: len,
            },
            tail,
            cost: n.cost + len,
        })
    }

    /// The roll before a new arc from `f` towards the offset `v`: towards the sample, or at random.
    fn arc_roll(&self, f: Frame, v: V3, rng: &mut impl Draw) -> f64 {
        let l = self.limits;
        let perp = v - f.e3 * v.dot(f.e3);
        if perp.norm() > 1e-9 && rng.unit() < AIMED_ROLL_SHARE {
            l.roll_towards(&f, perp.unit())
        } else if l.plane {
            if rng.unit() < 0.5 {
                0.0
            } else {
                PI
            }
        } else {
            rng.range(-PI, PI)
        }
    }

    fn best_path(&self) -> Option<TreePath> {
        let (index, connection, length) = self.best.as_ref()?;
        let mut pieces = connection.pieces.clone();
        let mut at = *index;
        let mut edges = Vec::new();
        while let Some(parent) = self.nodes[at].parent {
            edges.push(self.nodes[at].edge);
            at = parent;
        }
        edges.reverse();
        edges.append(&mut pieces);
        Some(TreePath {
            posture: self.nodes[*index].posture,
            pieces: edges,
            length: *length,
            nodes: self.nodes.len(),
        })
    }
}
