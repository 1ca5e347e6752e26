//! An independent reference planner: slow, simple, in f64, sharing no optimiser code with
//! `planner-core` (only its input types). It finds each form's global optimum by parameterising
//! the set of paths that end exactly on the target: the last two segments are solved in closed
//! form (arc-line tangent, line-arc quadratic, arc-arc circle intersection or torus root), the
//! remaining parameters (posture, earlier lengths, 3-D rolls) are swept on a dense grid (plane
//! mode) or sampled densely at random (3-D), and the best distinct starts are polished with
//! Nelder-Mead. See `docs/optimality.md`.

pub mod compare;
pub mod complete;
pub mod distance;
pub mod frame;
pub mod problem;
pub mod random;
pub mod search;
pub mod variant;

use frame::wrap;
use planner_core::{Form, FormOutcome, Scenario, SegmentKind};
use problem::{evaluate, Cand, Evaluation, Problem, Seg};
pub use search::Effort;

/// One segment of a reference path, as the planner reports segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefSegment {
    /// Arc or line.
    pub kind: SegmentKind,
    /// Length (mm).
    pub length: f64,
    /// Roll before the segment (degrees, in (-180, 180]).
    pub bevel_deg: f64,
}

/// The reference optimum of one form.
#[derive(Clone, Debug)]
pub struct RefSolution {
    /// The form.
    pub form: Form,
    /// F.
    pub objective: f64,
    /// L.
    pub length: f64,
    /// D.
    pub risk: f64,
    /// Smallest clearance.
    pub min_clearance: f64,
    /// Insertion angle about b1 (degrees).
    pub theta1_deg: f64,
    /// Insertion angle about b2 (degrees).
    pub theta2_deg: f64,
    /// The form's segments.
    pub segments: Vec<RefSegment>,
    /// Objective evaluations spent.
    pub evaluations: u64,
}

impl core::fmt::Display for RefSolution {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} F={:.4} L={:.4} D={:.5} minclr={:.3} theta=({:.4},{:.4})deg segs=[",
            self.form,
            self.objective,
            self.length,
            self.risk,
            self.min_clearance,
            self.theta1_deg,
            self.theta2_deg
        )?;
        for s in &self.segments {
            write!(f, " {}:{:.4}@{:.2}", s.kind.letter(), s.length, s.bevel_deg)?;
        }
        f.write_str(" ]")
    }
}

fn kinds(form: Form) -> Vec<SegmentKind> {
    (0..form.len()).map(|i| form.kind(i)).collect()
}

/// A reduced candidate written out as the form's segments (merged arcs cut into equal pieces).
fn expand(c: &Cand) -> Cand {
    let mut out = Cand::new(c.theta1, c.theta2);
    for s in c.segs() {
        let p = s.pieces.max(1);
        for k in 0..p {
            out.push(Seg {
                kind: s.kind,
                length: s.length / f64::from(p),
                roll: if k == 0 { s.roll } else { 0.0 },
                pieces: 1,
            });
        }
    }
    out
}

/// The global optimum of `form` for `scenario`, or `None` when no feasible path was found.
pub fn solve_form(scenario: &Scenario, form: Form, effort: Effort) -> Option<RefSolution> {
    solve_problem(&Problem::new(scenario), form, effort)
}

/// The global optimum of `form` for a problem (e.g. a scenario with its target moved).
pub fn solve_problem(pb: &Problem, form: Form, effort: Effort) -> Option<RefSolution> {
    let pb = pb.clone();
    let mut best: Option<search::Found> = None;
    let mut evaluations = 0;
    for (i, v) in variant::variants(&pb, &kinds(form)).iter().enumerate() {
        let seed = (form.index() as u64) << 32 | i as u64;
        let (found, n) = search::search(&pb, v, effort, seed);
        evaluations += n;
        if let Some(f) = found {
            if best.is_none_or(|b| f.objective < b.objective) {
                best = Some(f);
            }
        }
    }
    let found = best?;
    let cand = expand(&found.cand);
    let ev = evaluate(&pb, &cand, form.len());
    Some(RefSolution {
        form,
        objective: ev.objective,
        length: ev.length,
        risk: ev.risk,
        min_clearance: ev.min_clearance,
        theta1_deg: cand.theta1.to_degrees(),
        theta2_deg: cand.theta2.to_degrees(),
        segments: cand
            .segs()
            .iter()
            .map(|s| RefSegment {
                kind: s.kind,
                length: s.length,
                bevel_deg: wrap(s.roll).to_degrees(),
            })
            .collect(),
        evaluations,
    })
}

/// Measures, in f64 with the reference's own kinematics, the path a planner outcome describes.
pub fn evaluate_outcome(scenario: &Scenario, outcome: &FormOutcome) -> Evaluation {
    let pb = Problem::new(scenario);
    let mut c = Cand::new(
        f64::from(outcome.insertion.theta1_deg).to_radians(),
        f64::from(outcome.insertion.theta2_deg).to_radians(),
    );
    for s in &outcome.segments {
        c.push(Seg {
            kind: s.kind,
            length: f64::from(s.length),
            roll: f64::from(s.bevel_deg).to_radians(),
            pieces: 1,
        });
    }
    evaluate(&pb, &c, outcome.form.len())
}

/// Measures a reference solution again from its reported numbers (a self-check).
pub fn evaluate_solution(scenario: &Scenario, sol: &RefSolution) -> Evaluation {
    let pb = Problem::new(scenario);
    let mut c = Cand::new(sol.theta1_deg.to_radians(), sol.theta2_deg.to_radians());
    for s in &sol.segments {
        c.push(Seg {
            kind: s.kind,
            length: s.length,
            roll: s.bevel_deg.to_radians(),
            pieces: 1,
        });
    }
    evaluate(&pb, &c, sol.form.len())
}

/// Whether an evaluation is feasible for `scenario` (end within its tolerance).
pub fn is_feasible(scenario: &Scenario, ev: &Evaluation) -> bool {
    ev.feasible(
        &Problem::new(scenario),
        f64::from(scenario.target.tolerance),
    )
}

#[cfg(test)]
mod tests;
