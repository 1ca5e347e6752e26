//! A bounded feasible-path SQP for one form.
//!
//! The iterate always reaches the target: after every trial step the end-point equality is
//! restored by min-norm Gauss–Newton ([`restore`]), so the merit function is the objective itself
//! and the QP only needs the tangent step (Aₑ p = 0). Bounds, the tilt cone and the nearest
//! clearances enter the QP linearised; the risk term 1/d keeps iterates away from obstacles.
//! The Hessian of the Lagrangian is a damped BFGS approximation (Powell's damping keeps it
//! positive definite). Work is bounded: at most [`MAX_ITERATIONS`] iterations, each with at most
//! [`MAX_BACKTRACKS`] trial points, each restored in at most [`MAX_RESTORE`] Gauss–Newton steps.
//!
//! Every way a run can end from a feasible start is an `Ok` [`LocalSolution`] whose status says
//! which, with the first-order residual at the reported point ([`residual`]) to judge it by;
//! `Err` ([`SolveFailure`]) only when there is no feasible start to report.

mod hessian;
mod residual;
mod restore;
mod rows;
#[cfg(test)]
mod tests;

use crate::optim::basins::{Known, Memory, STATIONARY};
use crate::optim::objective::{Derivatives, Value};
use crate::optim::problem::{Problem, Vars, MAX_VARS};
use crate::optim::qp::{Qp, QpSolution, MAX_ROWS};
use crate::report::SolveStatus;
use residual::Multipliers;
pub use restore::{restore, restore_with};
pub(crate) use rows::{push_nearest_clearances, push_step_limits};
use rows::{tangent_qp, QpRows};

/// Iteration budget of one local solve.
pub const MAX_ITERATIONS: u32 = 40;
/// Trial points per line search.
pub const MAX_BACKTRACKS: u32 = 8;
/// Gauss–Newton steps per restoration.
pub const MAX_RESTORE: u32 = 8;
/// Largest change of any variable in one step (radians or radius-lengths).
const TRUST: f32 = 0.5;
/// Clearance rows given to the QP: the nearest obstacles only.
pub(crate) const QP_CLEARANCES: usize = MAX_ROWS - 2 * MAX_VARS - 1;

/// Result of a local solve.
#[derive(Clone, Debug)]
pub struct LocalSolution {
    /// The best point (feasible, on target).
    pub eval: Value,
    /// How the run ended (never [`SolveStatus::Infeasible`]: a run starts feasible and stays so).
    pub status: SolveStatus,
    /// Iterations taken.
    pub iterations: u32,
    /// Evaluations made (full and restoration).
    pub evaluations: u32,
    /// Infinity norm of the last QP step (zero when the run stopped in a known basin before
    /// solving one): what the stop test and the basin memory judge.
    pub step_norm: f32,
    /// The first-order residual at `eval` with the last QP's multipliers (see [`residual`]).
    pub kkt_residual: f32,
}

/// Why a local solve has nothing to report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SolveFailure {
    /// Restoration could not bring the start onto the target within its steps and the bounds
    /// (or met a value that is not finite on the way).
    StartOffTarget,
    /// The restored start touches an obstacle, leaves the tilt cone or has an objective that is
    /// not finite: the feasible-path SQP has no feasible point to descend from.
    StartInadmissible,
}

impl core::fmt::Display for SolveFailure {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            SolveFailure::StartOffTarget => "the start cannot be moved onto the target",
            SolveFailure::StartInadmissible => {
                "the start, moved onto the target, is not collision-free within the bounds"
            }
        })
    }
}

impl core::error::Error for SolveFailure {}

/// Runs the SQP from `x0` (restored onto the target first). `known` holds local solutions already
/// found for this problem, and the iterates that led there: a run that enters the basin of one
/// of them stops there (status [`SolveStatus::KnownBasin`], its objective no better than the
/// known one's; see [`crate::optim::basins`]). A run that ends stationary adds its solution and
/// its iterates.
pub fn solve(p: &Problem, x0: &Vars, known: &mut Known) -> Result<LocalSolution, SolveFailure> {
    let mut memory = Memory::start(known);
    // Judged by reference and returned as it came: a `LocalSolution` holds a whole path, and
    // moving it out of the `Result` and back in costs a copy on the device.
    let sol = run(p, x0, Some(&mut memory), MAX_ITERATIONS);
    match &sol {
        Ok(s) if ended_stationary(s.status) && s.step_norm < STATIONARY => {
            memory.settle(&s.eval.x, s.eval.objective, p.n);
        }
        // One stopped by its budget may lie on a slope that a later start would descend further.
        _ => memory.forget(),
    }
    sol
}

/// Whether a run that ended with `status` stopped where no descent is left to it.
fn ended_stationary(status: SolveStatus) -> bool {
    matches!(
        status,
        SolveStatus::Converged | SolveStatus::LineSearchStalled | SolveStatus::KnownBasin
    )
}

/// [`solve`] with at most `max_iterations` iterations and nothing known (a replan's fixed
/// budget).
pub fn solve_within(
    p: &Problem,
    x0: &Vars,
    max_iterations: u32,
) -> Result<LocalSolution, SolveFailure> {
    run(p, x0, None, max_iterations)
}

/// The SQP; its accepted iterates go to `memory`.
fn run(
    p: &Problem,
    x0: &Vars,
    mut memory: Option<&mut Memory>,
    max_iterations: u32,
) -> Result<LocalSolution, SolveFailure> {
    let max_iterations = max_iterations.min(MAX_ITERATIONS);
    let mut evals = 0u32;
    // Restored in place: on the device, a `Result` around the variables cost three unaligned
    // copies of them per solve.
    let mut x = *x0;
    if !restore(p, &mut x, &mut evals) {
        return Err(SolveFailure::StartOffTarget);
    }
    // Evaluated where it is kept: a `Value` holds the whole path, and copies of it cost more
    // than the rest of a short run's bookkeeping on the device.
    let start = p.value(&x);
    evals += 1;
    if !start.admissible(p) {
        return Err(SolveFailure::StartInadmissible);
    }
    // Two buffers: the current point and the line search's trial point (an accepted trial
    // becomes current by flipping `ci`, not by copying).
    let mut vals = [start.clone(), start];
    let mut ci = 0usize;
    let mut cur_d = p.derivatives(&vals[0]);
    let n = p.n;
    let mut status = SolveStatus::BudgetExhausted;
    let mut iterations = 0;
    let mut step_norm = f32::INFINITY;
    // The last QP solved (its multipliers go into the reported residual), in buffers that every
    // step overwrites: moving a step's solution through `Option`s cost the device more than the
    // residual.
    // A failed QP leaves `sol` as it was but has rebuilt its rows: the rows are double-buffered
    // so that those of the solution in `sol` survive it (`rows[ri]`).
    let mut sol = QpSolution::empty();
    let mut rows = [QpRows::empty(), QpRows::empty()];
    let mut ri = 0usize;
    let mut solved_any = false;
    let mut qp = Qp::new(n, hessian::initial(p), cur_d.grad);
    while iterations < max_iterations {
        iterations += 1;
        let cur = &vals[ci];
        if memory
            .as_ref()
            .is_some_and(|m| m.holds(&cur.x, cur.objective, n))
        {
            status = SolveStatus::KnownBasin;
            step_norm = 0.0;
            break;
        }
        if !step_qp(&mut qp, p, cur, &cur_d, (&mut sol, &mut rows[1 - ri])) {
            status = SolveStatus::QpFailed;
            break;
        }
        ri = 1 - ri;
        solved_any = true;
        let slope;
        (slope, step_norm) = slope_and_size(&cur_d.grad, &sol.p, n);
        if step_norm < 1e-5 || slope > -1e-6 * (1.0 + libm::fabsf(cur.objective)) {
            status = SolveStatus::Converged;
            break;
        }
        let (cur, trial) = current_and_trial(&mut vals, ci);
        if !line_search(p, cur, trial, &sol.p, slope, &mut evals) {
            // No decrease along a descent direction: stationary to f32 resolution, or held by a
            // constraint the QP's linearisation does not see.
            status = SolveStatus::LineSearchStalled;
            break;
        }
        if let Some(m) = memory.as_mut() {
            m.passed(&trial.x, trial.objective);
        }
        update_hessian(&mut qp.h, p, (cur, trial), &mut cur_d, &sol, &rows[ri]);
        ci = 1 - ci;
    }
    let multipliers = if solved_any {
        Multipliers::of(p, &sol, &rows[ri], &vals[ci])
    } else {
        Multipliers::none()
    };
    // `cur_d` holds the derivatives at the reported point.
    let kkt_residual = residual::residual_at(p, &vals[ci], &cur_d, &multipliers);
    let [a, b] = vals;
    Ok(LocalSolution {
        eval: if ci == 0 { a } else { b },
        status,
        iterations,
        evaluations: evals,
        step_norm,
        kkt_residual,
    })
}

/// The QP of the tangent step at `cur`, solved into `out` (its rows written there even when no
/// attempt succeeds); whether it was. In a passage between
/// obstacles the linearised clearances can be dependent (a singular working set): the QP is then
/// retried with fewer of them, since the line search keeps every clearance anyway. A
/// quasi-Newton matrix that has soaked up the huge curvature of 1/d in a thin passage can make
/// even that QP singular in f32: it is then reset to the model Hessian (and stays so for the
/// next steps).
fn step_qp(
    qp: &mut Qp,
    p: &Problem,
    cur: &Value,
    cur_d: &Derivatives,
    out: (&mut QpSolution, &mut QpRows),
) -> bool {
    let (sol, rows) = out;
    for attempt in 0..2 {
        if attempt == 1 {
            qp.h = hessian::model_hessian(p, cur, cur_d);
        }
        for clear_limit in [QP_CLEARANCES, 1, 0] {
            tangent_qp(qp, p, cur, cur_d, clear_limit, rows);
            if qp.solve_into(sol).is_ok() {
                return true;
            }
        }
    }
    false
}

/// The directional derivative of the objective along `step`, and the step's infinity norm.
fn slope_and_size(grad: &Vars, step: &Vars, n: usize) -> (f32, f32) {
    let mut slope = 0.0;
    let mut size = 0.0f32;
    for k in 0..n {
        slope += grad[k] * step[k];
        size = crate::fmath::max(size, libm::fabsf(step[k]));
    }
    (slope, size)
}

/// The current point `vals[ci]` and the other buffer, for the trial point.
fn current_and_trial(vals: &mut [Value; 2], ci: usize) -> (&Value, &mut Value) {
    let (first, second) = vals.split_at_mut(1);
    if ci == 0 {
        (&first[0], &mut second[0])
    } else {
        (&second[0], &mut first[0])
    }
}

/// Backtracking (Armijo) line search on the restored objective along `step` from `cur`, whose
/// directional derivative is `slope`. Leaves the accepted point in `trial` and says whether one
/// was found.
fn line_search(
    p: &Problem,
    cur: &Value,
    trial: &mut Value,
    step: &Vars,
    slope: f32,
    evals: &mut u32,
) -> bool {
    let mut t = 1.0f32;
    for _ in 0..MAX_BACKTRACKS {
        let mut xt = cur.x;
        for k in 0..p.n {
            xt[k] = crate::fmath::clamp(cur.x[k] + t * step[k], p.lower[k], p.upper[k]);
        }
        if restore_with(p, &mut xt, evals, &mut trial.geo) {
            p.value_of_drawn(&xt, trial);
            *evals += 1;
            if trial.admissible(p) && trial.objective <= cur.objective + 1e-4 * t * slope {
                return true;
            }
        }
        t *= 0.5;
    }
    false
}

/// The BFGS update of `h` for the accepted step from `cur` to `next`, with the multipliers of
/// the QP `sol` (rows `rows`) in the Lagrangian; leaves `next`'s derivatives in `cur_d` (on
/// entry `cur`'s).
fn update_hessian(
    h: &mut [Vars; MAX_VARS],
    p: &Problem,
    (cur, next): (&Value, &Value),
    cur_d: &mut Derivatives,
    sol: &QpSolution,
    rows: &QpRows,
) {
    let n = p.n;
    // By slot at either point; a row whose obstacle left the near set is left out of both.
    let mut clear_cur: heapless::Vec<(usize, f32), QP_CLEARANCES> = heapless::Vec::new();
    let mut clear_next: heapless::Vec<(usize, f32), QP_CLEARANCES> = heapless::Vec::new();
    for &(o, row) in &rows.clearances[..rows.n_clear] {
        if let (Some(a), Some(b)) = (cur.slot_of(o), next.slot_of(o)) {
            // Both within QP_CLEARANCES, the rows' own capacity.
            let _ = clear_cur.push((a, sol.mult[row]));
            let _ = clear_next.push((b, sol.mult[row]));
        }
    }
    let tilt_mult = if p.has_tilt() {
        sol.mult[rows.tilt]
    } else {
        0.0
    };
    let g_old = hessian::lagrangian_grad(p, &cur.x, cur_d, &sol.eq_mult, &clear_cur, tilt_mult);
    p.derivatives_into(next, cur_d);
    let g_new = hessian::lagrangian_grad(p, &next.x, cur_d, &sol.eq_mult, &clear_next, tilt_mult);
    let mut s = [0.0f32; MAX_VARS];
    let mut y = [0.0f32; MAX_VARS];
    for k in 0..n {
        s[k] = next.x[k] - cur.x[k];
        y[k] = g_new[k] - g_old[k];
    }
    hessian::bfgs_update(h, &s, &y, n);
}
