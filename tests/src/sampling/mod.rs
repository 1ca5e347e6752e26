//! A sampling-based completeness check for the planner: an RRT over needle tip frames, in f64
//! and independent of `planner-core` (only its `Scenario` is read), strong enough to find a
//! path of at most N segments whenever one exists with room to spare, and to find a short one.
//!
//! Three trees (each from its own seed) grow from the entry (roots at insertion headings drawn
//! in the tilt cone) by edges of 1 to 40 mm, a line or an arc after a roll, as long as the path
//! keeps to the planner's segment rules: a new segment at every roll or kind change, no two lines
//! in a row, each arc at most `max_arc_deg`, each line at most `max_line_length()`, at most N
//! segments. From every new node an exact goal connection is tried (arc then line or line then
//! arc in closed form; two arcs by a scanned root when neither passes); each tree's shortest
//! connected path is then shortened by a local search over its parameters, and the shortest of
//! them returned (none longer than the needle's insertable length). Every point of a returned
//! path keeps `min_clearance` plus [`CLEARANCE_MARGIN`] from every sphere.

pub mod arc_arc;
pub mod connect;
pub mod family;
pub mod limits;
pub mod route;
pub mod shorten;
pub mod tree;

pub use limits::{DistanceField, Limits, CLEARANCE_MARGIN};
use planner_core::{Scenario, SegmentKind};
use shorten::{shorten, Route};

/// One segment of a sampled path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledSegment {
    /// Arc or line.
    pub kind: SegmentKind,
    /// Roll about the heading before the segment (radians, in (-pi, pi]; 0 or pi in plane mode).
    pub roll: f64,
    /// Length (mm).
    pub length: f64,
}

/// A path the sampler found: collision-free, within every limit, ending on the target.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledPath {
    /// Insertion angle about b1 (radians; the reference's and the planner's convention).
    pub theta1: f64,
    /// Insertion angle about b2 (radians).
    pub theta2: f64,
    /// The segments, entry first.
    pub segments: Vec<SampledSegment>,
    /// Total length (mm).
    pub length: f64,
    /// Number of segments.
    pub segment_count: usize,
    /// Distance from the path's end to the target (mm).
    pub end_error: f64,
    /// Smallest clearance to any obstacle surface (mm; infinite without obstacles).
    pub min_clearance: f64,
    /// Length of the tree's path before shortening (mm).
    pub tree_length: f64,
    /// Nodes of the largest tree grown.
    pub nodes: usize,
}

impl core::fmt::Display for SampledPath {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "L={:.3} mm (tree {:.3}) N={} theta=({:.3},{:.3}) deg clear={:.3} end={:.1e} [",
            self.length,
            self.tree_length,
            self.segment_count,
            self.theta1.to_degrees(),
            self.theta2.to_degrees(),
            self.min_clearance,
            self.end_error
        )?;
        for s in &self.segments {
            write!(
                f,
                " {}:{:.3}@{:.2}",
                s.kind.letter(),
                s.length,
                s.roll.to_degrees()
            )?;
        }
        f.write_str(" ]")
    }
}

/// How hard the sampler tries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// Independent trees grown (each from its own seed), each path they find shortened.
    pub trees: usize,
    /// RRT iterations per tree (one sample, at most one new node each).
    pub iterations: usize,
    /// Route evaluations of the shortening pass, per split of the path.
    pub shortening: usize,
}

impl Budget {
    /// What the completeness tests use.
    pub const DEFAULT: Budget = Budget {
        trees: 3,
        iterations: 2000,
        shortening: 2500,
    };
}

/// The shortest path the sampler finds for `scenario` with `budget` from `seed`, or `None`.
pub fn sample(scenario: &Scenario, budget: Budget, seed: u64) -> Option<SampledPath> {
    sample_within(&Limits::new(scenario), budget, seed)
}

/// [`sample`] within `l` (a scenario's limits, perhaps with a distance field).
pub fn sample_within(l: &Limits, budget: Budget, seed: u64) -> Option<SampledPath> {
    let mut best: Option<SampledPath> = None;
    let mut nodes = 0;
    for k in 0..budget.trees as u64 {
        let tree_seed = seed.wrapping_mul(0x9E37_79B9).wrapping_add(k);
        let Some(found) = tree::grow(l, budget.iterations, tree_seed) else {
            continue;
        };
        nodes = nodes.max(found.nodes);
        let Some(p) = shortened(l, &found, budget.shortening, tree_seed) else {
            continue;
        };
        // A path longer than the needle cannot be inserted: the planner's check refuses it too.
        if p.length > l.max_length {
            continue;
        }
        if best.as_ref().is_none_or(|b| p.length < b.length) {
            best = Some(p);
        }
    }
    best.map(|p| SampledPath { nodes, ..p })
}

/// A tree's path in segments, shortened and measured.
fn shortened(
    l: &Limits,
    found: &tree::TreePath,
    evaluations: usize,
    seed: u64,
) -> Option<SampledPath> {
    let segments = route::normalize(&found.pieces);
    let (theta1, theta2) = found.posture;
    let measured = route::measure(l, theta1, theta2, &segments)?;
    let start = Route {
        theta1,
        theta2,
        segments,
        length: measured.length,
    };
    let best = shorten(l, start, evaluations, seed);
    let m = route::measure(l, best.theta1, best.theta2, &best.segments)?;
    Some(SampledPath {
        theta1: best.theta1,
        theta2: best.theta2,
        segment_count: best.segments.len(),
        segments: best.segments,
        length: m.length,
        end_error: (m.end.p - l.target).norm(),
        min_clearance: m.min_clearance,
        tree_length: found.length,
        nodes: found.nodes,
    })
}
