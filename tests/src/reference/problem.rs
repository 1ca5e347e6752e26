//! The planning problem in f64, a candidate path, and its exact objective.

use super::distance::{to_arc, to_line};
use super::frame::{entry_basis, insertion, Frame, V3};
use planner_core::model::scenario::{RiskMeasure, Workspace};
use planner_core::{Scenario, SegmentKind};

/// Most segments a candidate holds.
pub const MAX_SEGS: usize = 6;

/// The scenario's numbers in f64.
#[derive(Clone, Debug)]
pub struct Problem {
    /// Entry point.
    pub entry: V3,
    /// Entry basis (b1, b2, b3), b3 the nominal axis.
    pub basis: [V3; 3],
    /// Largest tilt (radians).
    pub max_tilt: f64,
    /// Target point.
    pub target: V3,
    /// Arc radius.
    pub rho: f64,
    /// Longest arc (mm).
    pub max_arc: f64,
    /// Longest line (mm).
    pub max_line: f64,
    /// Obstacles (centre, radius).
    pub obstacles: Vec<(V3, f64)>,
    /// Weights on L, D and N.
    pub w_length: f64,
    /// Weight on D.
    pub w_risk: f64,
    /// Weight on N.
    pub w_control: f64,
    /// D sums 1/d instead of averaging.
    pub risk_sum: bool,
    /// Clearances must exceed this.
    pub min_clearance: f64,
    /// Plane mode: theta2 = 0 and bevels 0 or pi.
    pub plane: bool,
    /// Insertable length (mm): the whole path's bound.
    pub needle_length: f64,
}

impl Problem {
    /// The f64 problem of a scenario.
    pub fn new(s: &Scenario) -> Problem {
        let entry = V3::from_f32(s.entry.position);
        let target = V3::from_f32(s.target.position);
        let rho = f64::from(s.needle.curvature_radius);
        let max_line = if s.needle.max_line_length > 0.0 {
            f64::from(s.needle.max_line_length)
        } else {
            2.0 * (target - entry).norm() + core::f64::consts::PI * rho
        };
        Problem {
            entry,
            basis: entry_basis(V3::from_f32(s.entry.direction)),
            max_tilt: f64::from(s.entry.max_tilt_deg).to_radians(),
            target,
            rho,
            max_arc: rho * f64::from(s.needle.max_arc_deg).to_radians(),
            max_line,
            obstacles: s
                .obstacles
                .iter()
                .map(|o| (V3::from_f32(o.center), f64::from(o.radius)))
                .collect(),
            w_length: f64::from(s.weights.length),
            w_risk: f64::from(s.weights.risk),
            w_control: f64::from(s.weights.control),
            risk_sum: s.options.risk == RiskMeasure::Sum,
            min_clearance: f64::from(s.options.min_clearance.max(0.0)),
            plane: s.options.workspace == Workspace::PlaneYz,
            needle_length: f64::from(s.needle.length),
        }
    }

    /// Longest segment of `kind` standing for `pieces` segments of the form: arcs joined without
    /// a turn are one arc, held to the longest arc whatever the pieces.
    pub fn bound(&self, kind: SegmentKind, _pieces: u8) -> f64 {
        match kind {
            SegmentKind::Arc => self.max_arc,
            SegmentKind::Line => self.max_line,
        }
    }

    /// The insertion frame at `(theta1, theta2)`.
    pub fn first_frame(&self, theta1: f64, theta2: f64) -> Frame {
        insertion(self.entry, &self.basis, theta1, theta2)
    }

    /// Whether the posture is inside the tilt cone (with a tiny slack).
    pub fn tilt_ok(&self, theta1: f64, theta2: f64) -> bool {
        theta1.cos() * theta2.cos() >= self.max_tilt.cos() - 1e-12
    }

    /// Scale for "exactly on target" checks.
    pub fn scale(&self) -> f64 {
        1.0 + (self.target - self.entry).norm()
    }
}

/// One segment: kind, length, the roll before it, and how many form segments it stands for
/// (consecutive arcs in one plane on the same side merge into one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seg {
    /// Arc or line.
    pub kind: SegmentKind,
    /// Length (mm).
    pub length: f64,
    /// Roll before the segment (radians).
    pub roll: f64,
    /// Form segments this one stands for (>= 1; lines always 1).
    pub pieces: u8,
}

impl Seg {
    /// Placeholder.
    pub const NONE: Seg = Seg {
        kind: SegmentKind::Line,
        length: 0.0,
        roll: 0.0,
        pieces: 1,
    };
}

/// A whole candidate path: posture and segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cand {
    /// Rotation about b1 (radians).
    pub theta1: f64,
    /// Rotation about b2 (radians).
    pub theta2: f64,
    /// Segments used.
    pub n: usize,
    /// Segments.
    pub segs: [Seg; MAX_SEGS],
}

impl Cand {
    /// An empty candidate at a posture.
    pub fn new(theta1: f64, theta2: f64) -> Cand {
        Cand {
            theta1,
            theta2,
            n: 0,
            segs: [Seg::NONE; MAX_SEGS],
        }
    }
    /// Appends a segment (ignored past capacity, which no form reaches).
    pub fn push(&mut self, s: Seg) {
        if self.n < MAX_SEGS {
            self.segs[self.n] = s;
            self.n += 1;
        }
    }
    /// The segments in use.
    pub fn segs(&self) -> &[Seg] {
        &self.segs[..self.n]
    }
    /// Frames at the start of each segment (after its roll) and at the end.
    pub fn frames(&self, pb: &Problem) -> ([Frame; MAX_SEGS + 1], usize) {
        let mut f = pb.first_frame(self.theta1, self.theta2);
        let mut out = [f; MAX_SEGS + 1];
        for (i, s) in self.segs().iter().enumerate() {
            f = f.roll(s.roll);
            out[i] = f;
            f = match s.kind {
                SegmentKind::Arc => f.arc(s.length, pb.rho),
                SegmentKind::Line => f.line(s.length),
            };
        }
        out[self.n] = f;
        (out, self.n)
    }
    /// Total length.
    pub fn length(&self) -> f64 {
        self.segs().iter().map(|s| s.length).sum()
    }
}

/// Everything measured about a candidate.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// End point.
    pub end: V3,
    /// Distance from the end to the target.
    pub target_error: f64,
    /// L.
    pub length: f64,
    /// Clearance d_i to each obstacle.
    pub clearances: Vec<f64>,
    /// Smallest clearance (infinite without obstacles).
    pub min_clearance: f64,
    /// D (infinite when some d_i <= 0).
    pub risk: f64,
    /// Posture in the tilt cone, lengths within [0, bound].
    pub within_bounds: bool,
    /// F = a1 L + a2 D + a4 N (meaningful when feasible).
    pub objective: f64,
}

impl Evaluation {
    /// End within `tolerance`, clearances above the floor, bounds respected.
    pub fn feasible(&self, pb: &Problem, tolerance: f64) -> bool {
        self.within_bounds
            && self.target_error <= tolerance
            && self.min_clearance > pb.min_clearance
    }
}

fn seg_distance(pb: &Problem, f: &Frame, s: &Seg, c: V3) -> f64 {
    match s.kind {
        SegmentKind::Arc => to_arc(f, s.length, pb.rho, c),
        SegmentKind::Line => to_line(f, s.length, c),
    }
}

fn bounds_ok(pb: &Problem, c: &Cand) -> bool {
    let segs = c.segs();
    let total: f64 = segs.iter().map(|s| s.length).sum();
    pb.tilt_ok(c.theta1, c.theta2)
        && total <= pb.needle_length * (1.0 + 1e-9)
        && joined_arcs_ok(pb, segs)
        && segs.iter().all(|s| {
            let max = pb.bound(s.kind, s.pieces);
            s.length.is_finite() && s.length >= -1e-9 && s.length <= max * (1.0 + 1e-12) + 1e-9
        })
}

/// Arcs that follow one another without a turn of the bevel (under 0.01 degree, the planner's
/// check's threshold) are one arc, held to the longest arc.
fn joined_arcs_ok(pb: &Problem, segs: &[Seg]) -> bool {
    let mut run = 0.0;
    let mut previous_arc = false;
    for s in segs {
        if s.kind != SegmentKind::Arc {
            previous_arc = false;
            continue;
        }
        let turn = s.roll.rem_euclid(core::f64::consts::TAU);
        let still = turn.min(core::f64::consts::TAU - turn) < 0.01f64.to_radians();
        run = if previous_arc && still {
            run + s.length
        } else {
            s.length
        };
        if run > pb.max_arc * (1.0 + 1e-9) + 1e-9 {
            return false;
        }
        previous_arc = true;
    }
    true
}

/// Measures a candidate completely; `control` is N (the form's segment count).
pub fn evaluate(pb: &Problem, c: &Cand, control: usize) -> Evaluation {
    let (frames, n) = c.frames(pb);
    let end = frames[n].p;
    let mut clearances = Vec::with_capacity(pb.obstacles.len());
    for &(centre, radius) in &pb.obstacles {
        let d = c
            .segs()
            .iter()
            .enumerate()
            .map(|(i, s)| seg_distance(pb, &frames[i], s, centre))
            .fold(f64::INFINITY, f64::min);
        clearances.push(d - radius);
    }
    let min_clearance = clearances.iter().copied().fold(f64::INFINITY, f64::min);
    let risk = risk_of(pb, &clearances);
    let length = c.length();
    Evaluation {
        end,
        target_error: (end - pb.target).norm(),
        length,
        within_bounds: bounds_ok(pb, c),
        objective: pb.w_length * length + pb.w_risk * risk + pb.w_control * control as f64,
        min_clearance,
        clearances,
        risk,
    }
}

fn risk_of(pb: &Problem, clearances: &[f64]) -> f64 {
    if clearances.is_empty() {
        return 0.0;
    }
    if clearances.iter().any(|&d| d <= 0.0) {
        return f64::INFINITY;
    }
    let sum: f64 = clearances.iter().map(|d| 1.0 / d).sum();
    if pb.risk_sum {
        sum
    } else {
        sum / clearances.len() as f64
    }
}

/// Merit values at or above this mark infeasible candidates (see [`score`]).
pub const INFEASIBLE: f64 = 1e6;

/// F of a candidate built to end exactly on the target when it is feasible. An infeasible one
/// that is in bounds and on target scores `INFEASIBLE` plus how deep it reaches into obstacles,
/// so a local search started next to a thin feasible region slides into it; out of bounds or
/// off the target scores infinity.
pub fn score(pb: &Problem, c: &Cand, control: usize) -> f64 {
    if !bounds_ok(pb, c) {
        return f64::INFINITY;
    }
    let (frames, n) = c.frames(pb);
    if (frames[n].p - pb.target).norm() > 1e-7 * pb.scale() {
        return f64::INFINITY;
    }
    let mut sum = 0.0;
    let mut violation = 0.0;
    for &(centre, radius) in &pb.obstacles {
        let mut d = f64::INFINITY;
        for (i, s) in c.segs().iter().enumerate() {
            d = d.min(seg_distance(pb, &frames[i], s, centre) - radius);
        }
        if d <= pb.min_clearance {
            violation += pb.min_clearance - d + 1e-9;
        } else {
            sum += 1.0 / d;
        }
    }
    if violation > 0.0 {
        return INFEASIBLE + violation;
    }
    let risk = if pb.risk_sum || pb.obstacles.is_empty() {
        sum
    } else {
        sum / pb.obstacles.len() as f64
    };
    pb.w_length * c.length() + pb.w_risk * risk + pb.w_control * control as f64
}
