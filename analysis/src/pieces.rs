//! A needle path as the RRT drives it: pieces of line or arc, each after a bevel roll; merged
//! into the segments a needle driver executes, scored with the optimiser's objective, and sampled
//! into points.

use needle_report::json::{finite, SegmentJson};
use planner_core::model::clearance::closest;
use planner_core::model::kinematics::{Frame, V3};
use planner_core::model::scenario::RiskMeasure;
use planner_core::{Scenario, SegmentKind};

/// One driven piece: roll the bevel by `roll` (radians), then drive `length` of `kind`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// Line or arc.
    pub kind: SegmentKind,
    /// Bevel rotation before the piece (radians; always 0 for lines, which spin anyway).
    pub roll: f32,
    /// Length (mm).
    pub length: f32,
}

/// A merged segment: what the needle driver executes between two bevel changes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Line or arc.
    pub kind: SegmentKind,
    /// Length (mm).
    pub length: f32,
    /// Bevel rotation before the segment (degrees).
    pub bevel_deg: f32,
}

impl Segment {
    /// The segment as the reports write one (`kind`, `length`, `bevel_deg`).
    pub fn to_json(&self) -> SegmentJson {
        SegmentJson {
            kind: self.kind.letter().to_string(),
            length: finite(self.length),
            bevel_deg: finite(self.bevel_deg),
        }
    }
}

/// Consecutive pieces that need no bevel change (lines after lines, arcs rolled by 0 after
/// arcs) merge into one segment; the number of segments is the control degree N.
pub fn merge(pieces: &[Piece]) -> Vec<Segment> {
    let mut out: Vec<Segment> = Vec::new();
    for p in pieces {
        if let Some(last) = out.last_mut() {
            if last.kind == p.kind && (p.kind == SegmentKind::Line || p.roll == 0.0) {
                last.length += p.length;
                continue;
            }
        }
        out.push(Segment {
            kind: p.kind,
            length: p.length,
            bevel_deg: wrap_deg(p.roll.to_degrees()),
        });
    }
    out
}

fn wrap_deg(d: f32) -> f32 {
    let w = d.rem_euclid(360.0);
    if w > 180.0 {
        w - 360.0
    } else {
        w
    }
}

/// A path measured with the optimiser's objective.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Score {
    /// L (mm).
    pub length: f32,
    /// D: mean (or sum, per the scenario) over obstacles of 1 / clearance.
    pub risk: f32,
    /// H: 1e6 if the path enters an obstacle, else 0 (always 0 for an RRT path).
    pub penalty: f32,
    /// N: segments after merging.
    pub control_degree: usize,
    /// F = a1 L + a2 D + a3 H + a4 N.
    pub objective: f32,
    /// Smallest clearance to any obstacle surface (mm).
    pub min_clearance: f32,
    /// Distance from the path's end to the target (mm).
    pub target_error: f32,
}

/// A scenario point as a vector.
pub(crate) fn v3(a: [f32; 3]) -> V3 {
    V3::new(a[0], a[1], a[2])
}

/// Scores the path that starts at `first` and drives `pieces`.
pub fn score(scenario: &Scenario, first: &Frame, pieces: &[Piece]) -> Score {
    let radius = scenario.needle.curvature_radius;
    let mut clear = vec![f32::INFINITY; scenario.obstacles.len()];
    let mut f = *first;
    for p in pieces {
        f = f.rolled(p.roll);
        for (i, ob) in scenario.obstacles.iter().enumerate() {
            let d = closest(&f, p.kind, p.length, radius, &v3(ob.center)).distance - ob.radius;
            clear[i] = clear[i].min(d);
        }
        f = f.advanced(p.kind, p.length, radius);
    }
    // As the planner's objective: D is infinite and H = 1e6 once any obstacle is entered.
    let blocked = clear.iter().any(|d| *d <= 0.0);
    let inverse: f32 = clear.iter().map(|d| 1.0 / d).sum();
    let risk = match (scenario.options.risk, clear.len()) {
        (_, 0) => 0.0,
        _ if blocked => f32::INFINITY,
        (RiskMeasure::Mean, n) => inverse / n as f32,
        (RiskMeasure::Sum, _) => inverse,
    };
    let length: f32 = pieces.iter().map(|p| p.length).sum();
    let n = merge(pieces).len();
    let w = &scenario.weights;
    let penalty = if blocked { 1e6 } else { 0.0 };
    Score {
        length,
        risk,
        penalty,
        control_degree: n,
        objective: w.length * length + w.risk * risk + w.penalty * penalty + w.control * n as f32,
        min_clearance: clear.iter().copied().fold(f32::INFINITY, f32::min),
        target_error: (f.p - v3(scenario.target.position)).norm(),
    }
}

/// Points along the path no more than `spacing` apart, entry first.
pub fn path_points(first: &Frame, pieces: &[Piece], radius: f32, spacing: f32) -> Vec<[f32; 3]> {
    let mut pts = vec![[first.p.x, first.p.y, first.p.z]];
    let mut f = *first;
    for p in pieces {
        f = f.rolled(p.roll);
        let n = (p.length / spacing).ceil().max(1.0) as usize;
        for k in 1..=n {
            let q = f.point_at(p.kind, p.length * k as f32 / n as f32, radius);
            pts.push([q.x, q.y, q.z]);
        }
        f = f.advanced(p.kind, p.length, radius);
    }
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn piece(kind: SegmentKind, roll: f32, length: f32) -> Piece {
        Piece { kind, roll, length }
    }

    #[test]
    fn merging_counts_bevel_changes() {
        use SegmentKind::{Arc, Line};
        let pi = core::f32::consts::PI;
        let pieces = [
            piece(Arc, 0.0, 10.0),
            piece(Arc, 0.0, 10.0),
            piece(Line, 0.0, 10.0),
            piece(Line, 0.0, 4.0),
            piece(Arc, pi, 10.0),
            piece(Arc, pi, 10.0), // flips back: a new segment
            piece(Arc, 0.0, 3.0),
        ];
        let segs = merge(&pieces);
        let kinds: Vec<_> = segs.iter().map(|s| (s.kind, s.length)).collect();
        assert_eq!(
            kinds,
            vec![(Arc, 20.0), (Line, 14.0), (Arc, 10.0), (Arc, 13.0)]
        );
        assert_eq!(segs[2].bevel_deg, 180.0);
    }
}
