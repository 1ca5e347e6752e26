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
use crate::model::scenario::MAX_OBSTACLES;
use crate::optim::objective::{Derivatives, Value};
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
    /// Of each obstacle's clearance (zero where the QP held no row).
    clearance: [f32; MAX_OBSTACLES],
}

impl Multipliers {
    /// No QP solved yet: every multiplier zero (the residual is then the objective's gradient).
    pub(super) fn none() -> Self {
        Multipliers {
            end: [0.0; 3],
            lower: [0.0; MAX_VARS],
            upper: [0.0; MAX_VARS],
            tilt: 0.0,
            clearance: [0.0; MAX_OBSTACLES],
        }
    }

    /// The multipliers of `sol`, a QP whose rows are `rows`.
    pub(super) fn of(p: &Problem, sol: &QpSolution, rows: &QpRows) -> Self {
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
            m.clearance[o] = sol.mult[row];
        }
        m
    }
}

/// One constraint as the residual sees it.
pub(super) struct Term<'a> {
    /// Its gradient.
    pub gradient: Gradient<'a>,
    /// Its multiplier.
    pub multiplier: f32,
    /// Its value c(x) for an inequality c(x) ≥ 0; `None` for an equality.
    pub inequality: Option<f32>,
}

/// A constraint's gradient: a row, or ± a unit vector (a bound).
pub(super) enum Gradient<'a> {
    /// A dense gradient.
    Row(&'a Vars),
    /// `sign` times unit vector `k`.
    Axis(usize, f32),
}

/// max(stationarity, complementarity) of the first `n` variables for the objective gradient
/// `grad` and the constraints `terms` (see the module's documentation).
pub(super) fn kkt_residual<'a>(
    n: usize,
    grad: &Vars,
    terms: impl IntoIterator<Item = Term<'a>>,
) -> f32 {
    let mut lagrangian = *grad;
    let mut complementarity = 0.0f32;
    for term in terms {
        let mu = term.multiplier;
        match term.gradient {
            Gradient::Row(a) => {
                for k in 0..n {
                    lagrangian[k] -= mu * a[k];
                }
            }
            Gradient::Axis(k, sign) => lagrangian[k] -= mu * sign,
        }
        if let Some(c) = term.inequality {
            let wrong_sign = crate::fmath::max(-mu, 0.0);
            // A zero multiplier owes nothing, however far the constraint is from its floor.
            let product = if mu == 0.0 { 0.0 } else { libm::fabsf(mu * c) };
            complementarity =
                crate::fmath::max(complementarity, crate::fmath::max(product, wrong_sign));
        }
    }
    let stationarity = lagrangian
        .iter()
        .take(n)
        .fold(0.0f32, |m, v| crate::fmath::max(m, libm::fabsf(*v)));
    crate::fmath::max(stationarity, complementarity)
}

/// The KKT residual of problem `p` at `at` (first derivatives `d`) with the multipliers `m`.
pub(super) fn residual_at(p: &Problem, at: &Value, d: &Derivatives, m: &Multipliers) -> f32 {
    let x = &at.x;
    let tilt_grad = p.tilt_margin_grad(x);
    let end = (0..p.m_eq).map(|r| Term {
        gradient: Gradient::Row(&d.jac[r]),
        multiplier: m.end[r],
        inequality: None,
    });
    let bounds = (0..p.n).flat_map(|k| {
        [
            Term {
                gradient: Gradient::Axis(k, 1.0),
                multiplier: m.lower[k],
                inequality: Some(x[k] - p.lower[k]),
            },
            Term {
                gradient: Gradient::Axis(k, -1.0),
                multiplier: m.upper[k],
                inequality: Some(p.upper[k] - x[k]),
            },
        ]
    });
    let tilt = p.has_tilt().then(|| Term {
        gradient: Gradient::Row(&tilt_grad),
        multiplier: m.tilt,
        inequality: Some(p.tilt_margin(x)),
    });
    let clearances = (0..p.scenario.obstacles.len()).map(|o| Term {
        gradient: Gradient::Row(&d.clearance_grad[o]),
        multiplier: m.clearance[o],
        inequality: Some(at.clearance[o] - p.min_clearance),
    });
    kkt_residual(
        p.n,
        &d.grad,
        end.chain(bounds).chain(tilt).chain(clearances),
    )
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
        let grad = vars(&[2.0 * x, 2.0 * y]);
        let row = vars(&[1.0, 1.0]);
        let term = Term {
            gradient: Gradient::Row(&row),
            multiplier: mu,
            inequality: Some(x + y - 2.0),
        };
        kkt_residual(2, &grad, [term])
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
        let grad = vars(&[0.0]);
        let term = Term {
            gradient: Gradient::Axis(0, 1.0),
            multiplier: -0.25,
            inequality: Some(0.0),
        };
        // Stationarity 0.25 (0 + 0.25) and the wrong sign 0.25.
        assert_eq!(kkt_residual(1, &grad, [term]), 0.25);
    }

    #[test]
    fn equalities_and_bounds_enter_stationarity() {
        // min −x subject to x ≤ 1 (the row −e₀, multiplier 1) and y = 0 (multiplier 0): zero.
        let grad = vars(&[-1.0, 0.0]);
        let eq = vars(&[0.0, 1.0]);
        let terms = [
            Term {
                gradient: Gradient::Axis(0, -1.0),
                multiplier: 1.0,
                inequality: Some(0.0),
            },
            Term {
                gradient: Gradient::Row(&eq),
                multiplier: 0.0,
                inequality: None,
            },
        ];
        assert_eq!(kkt_residual(2, &grad, terms), 0.0);
    }
}
