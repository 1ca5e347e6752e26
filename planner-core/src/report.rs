//! What the planner reports: one outcome per form tried, and the best of them.

use crate::model::form::{Form, SegmentKind, FORM_COUNT, MAX_CONTROL_DEGREE};
use serde::{Deserialize, Serialize};

/// How the solve that produced a form's reported path ended (for a feasible form), or that the
/// form has none. Every status but `Infeasible` comes with the path and its `kkt_residual`, which
/// says how nearly the first-order conditions hold there.
///
/// On the wire and in `plan --json` a status is its variant: new ones are only ever appended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SolveStatus {
    /// The SQP's stop test passed: its QP step (largest change of any variable) fell below 1e-5,
    /// or the step no longer promised a decrease of the objective beyond f32 resolution.
    Converged,
    /// The iteration budget ran out; the last iterate (feasible, on target) is reported.
    BudgetExhausted,
    /// No collision-free path of this form reaches the target within the bounds.
    Infeasible,
    /// No trial point along the QP's descent direction lowered the objective while staying on
    /// the target and clear of the obstacles: stationary to f32 resolution, or held by a
    /// constraint the QP's linearisation does not see (`kkt_residual` tells which).
    LineSearchStalled,
    /// The QP of a step could not be solved even with fewer clearance rows and a fresh Hessian;
    /// the last iterate is reported.
    QpFailed,
    /// The run came within a basin of a local solution an earlier start of the same problem had
    /// found, no worse than this point, and stopped there: it would have followed the earlier
    /// descent.
    KnownBasin,
}

/// The insertion posture: the nominal axis turned about the entry frame's first axis, then its second.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Insertion {
    /// Rotation about the entry frame's first axis (world x for the default frame), degrees.
    pub theta1_deg: f32,
    /// Rotation about the entry frame's second axis (world y for the default frame), degrees.
    pub theta2_deg: f32,
    /// Angle between the insertion direction and the nominal axis, degrees.
    pub tilt_deg: f32,
    /// Unit insertion direction.
    pub direction: [f32; 3],
}

/// One segment of a planned path.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SegmentPlan {
    /// Arc or line.
    pub kind: SegmentKind,
    /// Length along the needle (mm).
    pub length: f32,
    /// Rotation of the bevel about the shaft before this segment (degrees, in (-180, 180]).
    pub bevel_deg: f32,
}

/// Fixed-capacity segment list.
pub type Segments = heapless::Vec<SegmentPlan, MAX_CONTROL_DEGREE>;

/// The best path found for one form ("path classification").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FormOutcome {
    /// The form.
    pub form: Form,
    /// How the solve ended.
    pub status: SolveStatus,
    /// Whether the path passed the independent check (end point, clearances, bounds).
    pub feasible: bool,
    /// L: total length (mm).
    pub length: f32,
    /// D: risk degree.
    pub risk: f32,
    /// H: penalty degree (0 for a feasible path).
    pub penalty: f32,
    /// F = a1 L + a2 D + a3 H + a4 N.
    pub objective: f32,
    /// Smallest clearance to any obstacle surface (mm; infinite without obstacles).
    pub min_clearance: f32,
    /// Distance from the path's end to the target (mm).
    pub target_error: f32,
    /// Insertion posture.
    pub insertion: Insertion,
    /// The segments, entry first.
    pub segments: Segments,
    /// First-order (KKT) residual at the reported path, in the form's scaled variables (insertion
    /// angles and bevels in radians, lengths in arc radii): the larger of stationarity
    /// ‖∇F − Σ λⱼ ∇eⱼ − Σ μᵢ ∇cᵢ‖∞ and complementarity maxᵢ |μᵢ cᵢ| (a multiplier μᵢ < 0 counts
    /// as |μᵢ|), where eⱼ = 0 are the end-point rows, cᵢ ≥ 0 the bounds, the tilt cone and the
    /// clearances above the optimiser's floor (mm), all at the reported point, and λ, μ the
    /// multipliers of the last QP the run solved (zero if it solved none). Zero at a KKT point;
    /// NaN for an infeasible form.
    pub kkt_residual: f32,
    /// Optimiser iterations spent on this form (all starts).
    pub iterations: u32,
    /// Objective/constraint evaluations spent on this form.
    pub evaluations: u32,
}

impl FormOutcome {
    /// The outcome of a form for which no feasible path was found: no numbers, no effort.
    ///
    /// ```
    /// use planner_core::{Form, FormOutcome, SolveStatus};
    ///
    /// let none = FormOutcome::infeasible(Form::parse("RL").unwrap());
    /// assert!(!none.feasible && none.status == SolveStatus::Infeasible);
    /// assert!(none.objective.is_infinite() && none.length.is_nan());
    /// ```
    pub fn infeasible(form: Form) -> FormOutcome {
        FormOutcome {
            form,
            status: SolveStatus::Infeasible,
            feasible: false,
            length: f32::NAN,
            risk: f32::NAN,
            penalty: f32::NAN,
            objective: f32::INFINITY,
            min_clearance: f32::NAN,
            target_error: f32::NAN,
            insertion: Insertion::default(),
            segments: Segments::new(),
            kkt_residual: f32::NAN,
            iterations: 0,
            evaluations: 0,
        }
    }
}

/// Fixed-capacity list of per-form outcomes.
pub type FormOutcomes = heapless::Vec<FormOutcome, FORM_COUNT>;

/// The result of planning: every form tried, and which one won ("player killing").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanReport {
    /// One outcome per form tried, in catalogue order.
    pub forms: FormOutcomes,
    /// Index into `forms` of the feasible outcome with the lowest objective (planned under a
    /// collision bound that the lowest misses: the lowest among those that keep it); `None` when
    /// no form is feasible (the target is unreachable with the selected forms: `forms` says how each
    /// ended).
    pub best: Option<u8>,
}

impl PlanReport {
    /// The overall best outcome, if any form is feasible.
    pub fn best(&self) -> Option<&FormOutcome> {
        self.forms.get(usize::from(self.best?))
    }

    /// Total optimiser iterations.
    pub fn iterations(&self) -> u32 {
        self.forms.iter().map(|f| f.iterations).sum()
    }

    /// Total evaluations.
    pub fn evaluations(&self) -> u32 {
        self.forms.iter().map(|f| f.evaluations).sum()
    }
}
