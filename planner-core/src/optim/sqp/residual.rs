//! The first-order (KKT) residual of a reported point: how far it is from satisfying the
//! optimality conditions of its form's problem, whatever made the run stop there.
//!
//! The problem is: minimise F(x) subject to e(x) = 0 (the end point on the target) and
//! cᵢ(x) ≥ 0 (each bound, the tilt cone in 3-D, each clearance above the floor). With the
//! multipliers λ (equalities) and μ ≥ 0 (inequalities) of the last QP the run solved,
//!
//! - stationarity is ‖∇F − Σ λⱼ ∇eⱼ − Σ μᵢ ∇cᵢ‖∞,
//! - complementarity is maxᵢ |μᵢ · cᵢ(x)|, and a multiplier of the wrong sign counts as its size,
//!
//! all at the reported point, in the problem's scaled variables (radians and radius-lengths; F in
//! its own units, clearances in mm). The residual is the larger of the two.

use super::rows::QpRows;
use crate::optim::objective::{Derivatives, Value, MAX_NEAR};
use crate::optim::problem::{Problem, Vars, MAX_VARS};
use crate::optim::qp::QpSolution;

/// The multipliers of one QP, by constraint rather than by row.
#[derive(Clone, Debug)]
pub(super) struct Multipliers {
    /// Of the end-point rows.
    end: [f32; 3],
    /// Of each variable's lower bound.
    lower: Vars,
    /// Of each variable's upper bound.
    upper: Vars,
    /// Of the tilt cone.
    tilt: f32,
    /// Of the clearance of each slot of the reported point's near set (zero where the QP held
    /// no row).
    clearance: [f32; MAX_NEAR],
}

impl Multipliers {
    /// No QP solved yet: every multiplier zero (the residual is then the objective's gradient).
    pub(super) fn none() -> Self {
        Multipliers {
            end: [0.0; 3],
            lower: [0.0; MAX_VARS],
            upper: [0.0; MAX_VARS],
            tilt: 0.0,
            clearance: [0.0; MAX_NEAR],
        }
    }

    /// The multipliers of `sol`, a QP whose rows are `rows`, for the point `at` (a clearance
    /// row of an obstacle outside its near set is left out).
    pub(super) fn of(p: &Problem, sol: &QpSolution, rows: &QpRows, at: &Value) -> Self {
        let mut m = Multipliers::none();
        m.end = sol.eq_mult;
        for k in 0..p.n {
            m.lower[k] = sol.mult[rows.bounds + 2 * k];
            m.upper[k] = sol.mult[rows.bounds + 2 * k + 1];
        }
        if p.has_tilt() {
            m.tilt = sol.mult[rows.tilt];
        }
        for &(o, row) in &rows.clearances[..rows.n_clear] {
            if let Some(slot) = at.slot_of(o) {
                m.clearance[slot] = sol.mult[row];
            }
        }
        m
    }
}

/// The residual accumulated constraint by constraint (see the module's documentation): the
/// Lagrangian's gradient so far and the worst complementarity so far.
pub(super) struct Residual {
    n: usize,
    lagrangian: Vars,
    complementarity: f32,
}

impl Residual {
    /// The first `n` variables, objective gradient `grad`, no constraint yet.
    pub(super) fn new(n: usize, grad: &Vars) -> Self {
        Residual {
            n,
            lagrangian: *grad,
            complementarity: 0.0,
        }
    }

    /// An equality with gradient `a` and multiplier `mu`.
    // One copy of the row loop for every constraint: it runs a few times per solve, and
    // unrolled at each call it cost the firmware a kilobyte of flash.
    #[inline(never)]
    pub(super) fn equality(&mut self, a: &Vars, mu: f32) {
        for k in 0..self.n {
            self.lagrangian[k] -= mu * a[k];
        }
    }

    /// An inequality c(x) ≥ 0 with gradient `a`, multiplier `mu` and value `c`.
    pub(super) fn inequality(&mut self, a: &Vars, mu: f32, c: f32) {
        self.equality(a, mu);
        self.owe(mu, c);
    }

    /// The bound `sign` · xₖ ≥ … (gradient `sign` times unit vector `k`), multiplier `mu`, value
    /// `c`.
    pub(super) fn bound(&mut self, k: usize, sign: f32, mu: f32, c: f32) {
        self.lagrangian[k] -= mu * sign;
        self.owe(mu, c);
    }

    #[inline(never)]
    fn owe(&mut self, mu: f32, c: f32) {
        let wrong_sign = crate::fmath::max(-mu, 0.0);
        // A zero multiplier owes nothing, however far the constraint is from its floor.
        let product = if mu == 0.0 { 0.0 } else { libm::fabsf(mu * c) };
        self.complementarity =
            crate::fmath::max(self.complementarity, crate::fmath::max(product, wrong_sign));
    }

    /// max(stationarity, complementarity).
    pub(super) fn value(&self) -> f32 {
        let stationarity = self
            .lagrangian
            .iter()
            .take(self.n)
            .fold(0.0f32, |m, v| crate::fmath::max(m, libm::fabsf(*v)));
        crate::fmath::max(stationarity, self.complementarity)
    }
}

/// The KKT residual of problem `p` at `at` (first derivatives `d`) with the multipliers `m`.
/// Written as plain loops: on the device an iterator chain of constraint terms cost several
/// times as much; kept out of the SQP's loop (it runs once per solve).
#[inline(never)]
pub(super) fn residual_at(p: &Problem, at: &Value, d: &Derivatives, m: &Multipliers) -> f32 {
    let x = &at.x;
    let mut r = Residual::new(p.n, &d.grad);
    for (row, mu) in d.jac.iter().zip(m.end).take(p.m_eq) {
        r.equality(row, mu);
    }
    for k in 0..p.n {
        r.bound(k, 1.0, m.lower[k], x[k] - p.lower[k]);
        r.bound(k, -1.0, m.upper[k], p.upper[k] - x[k]);
    }
    if p.has_tilt() {
        r.inequality(&p.tilt_margin_grad(x), m.tilt, p.tilt_margin(x));
    }
    for o in 0..at.near_count.min(MAX_NEAR) {
        r.inequality(
            &d.clearance_grad[o],
            m.clearance[o],
            at.clearance[o] - p.min_clearance,
        );
    }
    r.value()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vars(values: &[f32]) -> Vars {
        let mut v = [0.0; MAX_VARS];
        v[..values.len()].copy_from_slice(values);
        v
    }

    /// min x² + y² subject to x + y − 2 ≥ 0: the optimum is (1, 1) with μ = 2.
    fn residual_of_the_disc_problem(x: f32, y: f32, mu: f32) -> f32 {
        let mut r = Residual::new(2, &vars(&[2.0 * x, 2.0 * y]));
        r.inequality(&vars(&[1.0, 1.0]), mu, x + y - 2.0);
        r.value()
    }

    #[test]
    fn zero_at_the_optimum_and_clearly_positive_off_it() {
        assert_eq!(residual_of_the_disc_problem(1.0, 1.0, 2.0), 0.0);
        // (2, 0) is feasible and on the constraint, but not stationary: the best multiplier
        // (least squares, μ = 2) leaves ∇F − μ a = (2, −2).
        assert_eq!(residual_of_the_disc_problem(2.0, 0.0, 2.0), 2.0);
        // Off the constraint, a multiplier that is not zero breaks complementarity.
        assert_eq!(residual_of_the_disc_problem(1.5, 1.5, 3.0), 3.0);
    }

    #[test]
    fn a_multiplier_of_the_wrong_sign_counts() {
        // At (1, 1) with μ = −0.5: stationarity |2 + 0.5| = 2.5, and the sign violation 0.5.
        assert_eq!(residual_of_the_disc_problem(1.0, 1.0, -0.5), 2.5);
        let mut r = Residual::new(1, &vars(&[0.0]));
        r.bound(0, 1.0, -0.25, 0.0);
        // Stationarity 0.25 (0 + 0.25) and the wrong sign 0.25.
        assert_eq!(r.value(), 0.25);
    }

    #[test]
    fn equalities_and_bounds_enter_stationarity() {
        // min −x subject to x ≤ 1 (the row −e₀, multiplier 1) and y = 0 (multiplier 0): zero.
        let mut r = Residual::new(2, &vars(&[-1.0, 0.0]));
        r.bound(0, -1.0, 1.0, 0.0);
        r.equality(&vars(&[0.0, 1.0]), 0.0);
        assert_eq!(r.value(), 0.0);
        // Without the bound's multiplier the gradient is left: stationarity 1.
        let mut r = Residual::new(2, &vars(&[-1.0, 0.0]));
        r.equality(&vars(&[0.0, 1.0]), 0.0);
        assert_eq!(r.value(), 1.0);
    }
}
