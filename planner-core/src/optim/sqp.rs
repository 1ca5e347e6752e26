//! A bounded feasible-path SQP for one form.
//!
//! The iterate always reaches the target: after every trial step the end-point equality is
//! restored by min-norm Gauss–Newton ([`restore`]), so the merit function is the objective itself
//! and the QP only needs the tangent step (Aₑ p = 0). Bounds, the tilt cone and the nearest
//! clearances enter the QP linearised; the risk term 1/d keeps iterates away from obstacles.
//! The Hessian of the Lagrangian is a damped BFGS approximation (Powell's damping keeps it
//! positive definite). Work is bounded: at most [`MAX_ITERATIONS`] iterations, each with at most
//! [`MAX_BACKTRACKS`] trial points, each restored in at most [`MAX_RESTORE`] Gauss–Newton steps.

use crate::model::scenario::MAX_OBSTACLES;
use crate::optim::basins::{Known, Memory, STATIONARY};
use crate::optim::linalg;
use crate::optim::objective::{Derivatives, Value};
use crate::optim::problem::{Problem, Vars, MAX_VARS};
use crate::optim::qp::{Qp, MAX_ROWS};
use crate::report::SolveStatus;

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
    /// How the solve ended.
    pub status: SolveStatus,
    /// Iterations taken.
    pub iterations: u32,
    /// Evaluations made (full and restoration).
    pub evaluations: u32,
    /// Size of the last QP step (a KKT residual: zero at a stationary point).
    pub step_norm: f32,
}

/// End-point tolerance the optimiser solves to (mm): a hundredth of the scenario's, at most 1 um,
/// but never finer than f32 resolves at these coordinates (a finer one cannot be met and would
/// fail restorations that in fact reached the target).
pub fn equality_tolerance(p: &Problem) -> f32 {
    p.equality_tolerance
}

/// Moves `x` onto the target manifold (end point = target) by min-norm Gauss–Newton steps that
/// keep the bounds. Returns whether the end is within the tolerance; `evals` counts kinematics.
pub fn restore(p: &Problem, x: &mut Vars, evals: &mut u32) -> bool {
    let mut geo = p.geometry(x);
    restore_with(p, x, evals, &mut geo)
}

/// [`restore`], leaving in `geo` the path of the last `x` (the restored one on success: a line
/// search evaluates it next and need not draw it again).
pub fn restore_with(
    p: &Problem,
    x: &mut Vars,
    evals: &mut u32,
    geo: &mut crate::model::kinematics::PathGeometry,
) -> bool {
    let tol = equality_tolerance(p);
    for _ in 0..=MAX_RESTORE {
        p.geometry_into(x, geo);
        let geo = &*geo;
        let r = p.end_residual(geo);
        *evals += 1;
        let norm = crate::fmath::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if !norm.is_finite() {
            return false;
        }
        if norm <= tol {
            return true;
        }
        // Not there yet: the Jacobian of the same rows.
        let (_, jac) = p.end_rows(geo, &p.screws(x, geo));
        // Variables pinned at a bound that the step would push further out are held fixed.
        let mut free = [true; MAX_VARS];
        let mut delta = [0.0f32; MAX_VARS];
        for _ in 0..p.n {
            if !min_norm_step(p, &jac, &r, &free, &mut delta) {
                return false;
            }
            let mut changed = false;
            for k in 0..p.n {
                let out_low = x[k] <= p.lower[k] && delta[k] < 0.0;
                let out_high = x[k] >= p.upper[k] && delta[k] > 0.0;
                if free[k] && (out_low || out_high) {
                    free[k] = false;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        // Limit the step so that Gauss–Newton stays in its region of validity.
        let big = delta
            .iter()
            .take(p.n)
            .fold(0.0f32, |m, v| crate::fmath::max(m, libm::fabsf(*v)));
        let shrink = if big > TRUST { TRUST / big } else { 1.0 };
        for k in 0..p.n {
            x[k] = crate::fmath::clamp(x[k] + shrink * delta[k], p.lower[k], p.upper[k]);
        }
    }
    false
}

/// delta = -Jᶠᵀ (Jᶠ Jᶠᵀ)⁻¹ r over the free columns (with a tiny Tikhonov term).
fn min_norm_step(
    p: &Problem,
    jac: &[Vars; 3],
    r: &[f32; 3],
    free: &[bool; MAX_VARS],
    delta: &mut Vars,
) -> bool {
    let m = p.m_eq;
    let mut a = [[0.0f32; 3]; 3];
    for i in 0..m {
        for j in 0..m {
            for k in 0..p.n {
                if free[k] {
                    a[i][j] += jac[i][k] * jac[j][k];
                }
            }
        }
    }
    let trace = (0..m).map(|i| a[i][i]).sum::<f32>();
    for (i, row) in a.iter_mut().enumerate().take(m) {
        row[i] += 1e-7 * trace + 1e-12;
    }
    let mut y = [r[0], r[1], r[2]];
    if !linalg::solve(&mut a, &mut y, m) {
        return false;
    }
    for k in 0..MAX_VARS {
        delta[k] = 0.0;
        if k < p.n && free[k] {
            for i in 0..m {
                delta[k] -= jac[i][k] * y[i];
            }
        }
    }
    true
}

/// Gradient of the Lagrangian for the nonlinear constraints (end point, clearances, tilt).
fn lagrangian_grad(
    p: &Problem,
    x: &Vars,
    e: &Derivatives,
    eq: &[f32; 3],
    clear: &[(usize, f32)],
    tilt_mult: f32,
) -> Vars {
    let mut g = e.grad;
    let tg = p.tilt_margin_grad(x);
    for k in 0..p.n {
        for (r, mu) in eq.iter().enumerate().take(p.m_eq) {
            g[k] -= mu * e.jac[r][k];
        }
        for &(o, mu) in clear {
            g[k] -= mu * e.clearance_grad[o][k];
        }
        g[k] -= tilt_mult * tg[k];
    }
    g
}

/// Runs the SQP from `x0` (restored onto the target first). `None` when the start cannot be made
/// feasible. `known` holds local solutions already found for this problem, and the iterates
/// that led there: a run that enters the basin of one of them stops there (status `Converged`,
/// its objective no better than the known one's; see [`crate::optim::basins`]). A run that ends
/// stationary adds its solution and its iterates.
pub fn solve(p: &Problem, x0: &Vars, known: &mut Known) -> Option<LocalSolution> {
    let mut memory = Memory::start(known);
    let Some(sol) = run(p, x0, Some(&mut memory), MAX_ITERATIONS) else {
        memory.forget();
        return None;
    };
    if sol.status == SolveStatus::Converged && sol.step_norm < STATIONARY {
        memory.settle(&sol.eval.x, sol.eval.objective, p.n);
    } else {
        // One stopped by its budget may lie on a slope that a later start would descend further.
        memory.forget();
    }
    Some(sol)
}

/// [`solve`] with at most `max_iterations` iterations and nothing known (a replan's fixed
/// budget).
pub fn solve_within(p: &Problem, x0: &Vars, max_iterations: u32) -> Option<LocalSolution> {
    run(p, x0, None, max_iterations)
}

/// The SQP; its accepted iterates go to `memory`.
fn run(
    p: &Problem,
    x0: &Vars,
    mut memory: Option<&mut Memory>,
    max_iterations: u32,
) -> Option<LocalSolution> {
    let max_iterations = max_iterations.min(MAX_ITERATIONS);
    let mut evals = 0u32;
    let mut x = *x0;
    if !restore(p, &mut x, &mut evals) {
        return None;
    }
    // Two buffers: the current point and the line search's trial point (an accepted trial
    // becomes current by flipping `ci`, not by copying).
    let start = p.value(&x);
    let mut vals = [start.clone(), start];
    let mut ci = 0usize;
    evals += 1;
    if !vals[0].admissible(p) {
        return None;
    }
    let mut cur_d = p.derivatives(&vals[0]);
    let n = p.n;
    let gamma = p.scenario.weights.length * p.radius + 1.0;
    let mut h = [[0.0f32; MAX_VARS]; MAX_VARS];
    for (i, row) in h.iter_mut().enumerate().take(n) {
        row[i] = gamma;
    }
    let mut status = SolveStatus::BudgetExhausted;
    let mut iterations = 0;
    let mut step_norm = f32::INFINITY;
    let mut qp = Qp::new(n, h, cur_d.grad);
    while iterations < max_iterations {
        iterations += 1;
        let cur = &vals[ci];
        if memory
            .as_ref()
            .is_some_and(|m| m.holds(&cur.x, cur.objective, n))
        {
            status = SolveStatus::Converged;
            step_norm = 0.0;
            break;
        }
        // The QP of the tangent step. In a passage between obstacles the linearised clearances
        // can be dependent (a singular working set): the QP is then retried with fewer of them,
        // since the line search keeps every clearance anyway.
        // A quasi-Newton matrix that has soaked up the huge curvature of 1/d in a thin passage
        // can make even that QP singular in f32: it is then reset to the model Hessian.
        let mut solved = None;
        for attempt in 0..2 {
            if attempt == 1 {
                qp.h = model_hessian(p, cur, &cur_d);
            }
            for clear_limit in [QP_CLEARANCES, 1, 0] {
                let rows = tangent_qp(&mut qp, p, cur, &cur_d, clear_limit);
                if let Ok(sol) = qp.solve() {
                    solved = Some((sol, rows));
                    break;
                }
            }
            if solved.is_some() {
                break;
            }
        }
        let Some((sol, rows)) = solved else {
            status = SolveStatus::BudgetExhausted;
            break;
        };
        let (clear_rows, n_clear, tilt_row) = (rows.clearances, rows.n_clear, rows.tilt);
        let mut slope = 0.0;
        step_norm = 0.0f32;
        for k in 0..n {
            slope += cur_d.grad[k] * sol.p[k];
            step_norm = crate::fmath::max(step_norm, libm::fabsf(sol.p[k]));
        }
        if step_norm < 1e-5 || slope > -1e-6 * (1.0 + libm::fabsf(cur.objective)) {
            status = SolveStatus::Converged;
            break;
        }
        // Backtracking line search on the restored objective.
        let mut t = 1.0f32;
        let mut accepted = false;
        let (first, second) = vals.split_at_mut(1);
        let (cur, trial) = if ci == 0 {
            (&first[0], &mut second[0])
        } else {
            (&second[0], &mut first[0])
        };
        for _ in 0..MAX_BACKTRACKS {
            let mut xt = cur.x;
            for k in 0..n {
                xt[k] = crate::fmath::clamp(cur.x[k] + t * sol.p[k], p.lower[k], p.upper[k]);
            }
            if restore_with(p, &mut xt, &mut evals, &mut trial.geo) {
                p.value_of_drawn(&xt, trial);
                evals += 1;
                if trial.admissible(p) && trial.objective <= cur.objective + 1e-4 * t * slope {
                    accepted = true;
                    break;
                }
            }
            t *= 0.5;
        }
        if !accepted {
            // No decrease along a descent direction: stationary to f32 resolution.
            status = SolveStatus::Converged;
            break;
        }
        let next: &Value = trial;
        if let Some(m) = memory.as_mut() {
            m.passed(&next.x, next.objective);
        }
        let clear: heapless::Vec<(usize, f32), QP_CLEARANCES> = clear_rows[..n_clear]
            .iter()
            .map(|&(o, row)| (o, sol.mult[row]))
            .collect();
        let tilt_mult = if p.has_tilt() {
            sol.mult[tilt_row]
        } else {
            0.0
        };
        let g_old = lagrangian_grad(p, &cur.x, &cur_d, &sol.eq_mult, &clear, tilt_mult);
        p.derivatives_into(next, &mut cur_d);
        let g_new = lagrangian_grad(p, &next.x, &cur_d, &sol.eq_mult, &clear, tilt_mult);
        let mut s = [0.0f32; MAX_VARS];
        let mut y = [0.0f32; MAX_VARS];
        for k in 0..n {
            s[k] = next.x[k] - cur.x[k];
            y[k] = g_new[k] - g_old[k];
        }
        bfgs_update(&mut qp.h, &s, &y, n);
        ci = 1 - ci;
    }
    let [a, b] = vals;
    Some(LocalSolution {
        eval: if ci == 0 { a } else { b },
        status,
        iterations,
        evaluations: evals,
        step_norm,
    })
}

/// Largest curvature of the model Hessian relative to its diagonal floor.
const MAX_CONDITION: f32 = 1e4;

/// A Hessian model from scratch: the length term's scale on the diagonal plus the Gauss–Newton
/// curvature of the risk term, 2 a2 s / d³ ∇d ∇dᵀ per obstacle (s: 1/count for the mean), which
/// dominates near an obstacle.
fn model_hessian(p: &Problem, cur: &Value, cur_d: &Derivatives) -> [Vars; MAX_VARS] {
    let n = p.n;
    let gamma = p.scenario.weights.length * p.radius + 1.0;
    let mut h = [[0.0f32; MAX_VARS]; MAX_VARS];
    for (i, row) in h.iter_mut().enumerate().take(n) {
        row[i] = gamma;
    }
    let risk = p.scenario.weights.risk * p.risk_scale();
    for o in 0..p.scenario.obstacles.len() {
        let d = cur.clearance[o];
        if !(d > 0.0) || risk == 0.0 {
            continue;
        }
        let g = &cur_d.clearance_grad[o];
        // Capped so that the matrix stays well conditioned in f32; the line search makes up for
        // the steps this lets grow too long.
        let g2: f32 = g.iter().take(n).map(|v| v * v).sum();
        let w = (2.0 * risk / (d * d * d)).min(MAX_CONDITION * gamma / g2.max(1e-12));
        for i in 0..n {
            for j in 0..n {
                h[i][j] += w * g[i] * g[j];
            }
        }
    }
    h
}

/// Which QP rows hold the nonlinear inequalities (for their multipliers).
struct QpRows {
    /// (obstacle, row) of each clearance row.
    clearances: [(usize, usize); QP_CLEARANCES],
    n_clear: usize,
    tilt: usize,
}

/// The QP of the tangent step at `cur`: bounds within the trust box, the tilt cone (3-D) and the
/// `clear_limit` nearest clearances, linearised; the Hessian is the one in `qp`.
fn tangent_qp(
    qp: &mut Qp,
    p: &Problem,
    cur: &Value,
    cur_d: &Derivatives,
    clear_limit: usize,
) -> QpRows {
    qp.reset_rows(p.n, &cur_d.grad);
    let mut rows = QpRows {
        clearances: [(0, 0); QP_CLEARANCES],
        n_clear: 0,
        tilt: push_step_limits(qp, p, &cur.x, cur_d),
    };
    push_nearest_clearances(
        qp,
        p,
        cur,
        cur_d,
        clear_limit,
        |_| true,
        |o, row| {
            rows.clearances[rows.n_clear] = (o, row);
            rows.n_clear += 1;
        },
    );
    rows
}

/// Pushes the rows every step at `x` keeps: the end point fixed (Aₑ p = 0), each variable within
/// its bounds and the trust box, and in 3-D the tilt cone (linearised). Returns the tilt row.
pub(crate) fn push_step_limits(qp: &mut Qp, p: &Problem, x: &Vars, d: &Derivatives) -> usize {
    for r in 0..p.m_eq {
        qp.push_eq(&d.jac[r]);
    }
    for k in 0..p.n {
        qp.push_axis(k, 1.0, crate::fmath::max(p.lower[k] - x[k], -TRUST));
        qp.push_axis(k, -1.0, -crate::fmath::min(p.upper[k] - x[k], TRUST));
    }
    let tilt = qp.m;
    if p.has_tilt() {
        qp.push_row(&p.tilt_margin_grad(x), -p.tilt_margin(x));
    }
    tilt
}

/// Pushes the linearised clearances (kept at the floor) of up to `limit` obstacles for which
/// `eligible` holds, nearest first; `pushed(obstacle, row)` is told each row.
pub(crate) fn push_nearest_clearances(
    qp: &mut Qp,
    p: &Problem,
    cur: &Value,
    d: &Derivatives,
    limit: usize,
    eligible: impl Fn(usize) -> bool,
    mut pushed: impl FnMut(usize, usize),
) {
    let obstacles = p.scenario.obstacles.len();
    let mut taken = [false; MAX_OBSTACLES];
    for _ in 0..limit.min(obstacles) {
        let mut best: Option<usize> = None;
        for o in 0..obstacles {
            if !taken[o] && eligible(o) && best.is_none_or(|b| cur.clearance[o] < cur.clearance[b])
            {
                best = Some(o);
            }
        }
        let Some(o) = best else { break };
        taken[o] = true;
        let row = qp.m;
        if qp.push_row(&d.clearance_grad[o], p.min_clearance - cur.clearance[o]) {
            pushed(o, row);
        }
    }
}

/// Powell-damped BFGS update of `h` with step `s` and gradient change `y`.
fn bfgs_update(h: &mut [Vars; MAX_VARS], s: &Vars, y: &Vars, n: usize) {
    let mut hs = [0.0f32; MAX_VARS];
    let mut shs = 0.0f32;
    let mut sy = 0.0f32;
    for i in 0..n {
        for j in 0..n {
            hs[i] += h[i][j] * s[j];
        }
        shs += s[i] * hs[i];
        sy += s[i] * y[i];
    }
    if !(shs > 1e-12) {
        return;
    }
    let theta = if sy >= 0.2 * shs {
        1.0
    } else {
        0.8 * shs / (shs - sy)
    };
    let mut r = [0.0f32; MAX_VARS];
    let mut sr = 0.0f32;
    for i in 0..n {
        r[i] = theta * y[i] + (1.0 - theta) * hs[i];
        sr += s[i] * r[i];
    }
    if !(sr > 1e-12) {
        return;
    }
    for i in 0..n {
        for j in 0..n {
            h[i][j] += r[i] * r[j] / sr - hs[i] * hs[j] / shs;
        }
    }
}
