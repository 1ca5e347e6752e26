//! The Hessian of the Lagrangian the SQP's QPs use: a damped BFGS approximation, started from
//! (and, when it has made a QP singular, reset to) a model built from the objective's terms.

use crate::optim::objective::{Derivatives, Value};
use crate::optim::problem::{Problem, Vars, MAX_VARS};

/// The starting Hessian: the length term's scale on the diagonal.
pub(super) fn initial(p: &Problem) -> [Vars; MAX_VARS] {
    let gamma = p.scenario.weights.length * p.radius + 1.0;
    let mut h = [[0.0f32; MAX_VARS]; MAX_VARS];
    for (i, row) in h.iter_mut().enumerate().take(p.n) {
        row[i] = gamma;
    }
    h
}

/// Largest curvature of the model Hessian relative to its diagonal floor.
const MAX_CONDITION: f32 = 1e4;

/// A Hessian model from scratch: the length term's scale on the diagonal plus the Gauss–Newton
/// curvature of the risk term, 2 a2 s / d³ ∇d ∇dᵀ per obstacle of the near set (s: 1/count for
/// the mean), which dominates near an obstacle.
pub(super) fn model_hessian(p: &Problem, cur: &Value, cur_d: &Derivatives) -> [Vars; MAX_VARS] {
    let n = p.n;
    let gamma = p.scenario.weights.length * p.radius + 1.0;
    let mut h = initial(p);
    let risk = p.scenario.weights.risk * p.risk_scale();
    for o in 0..cur.near_count {
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

/// Gradient of the Lagrangian for the nonlinear constraints (end point, clearances, tilt);
/// `clear` holds (slot, multiplier) of the clearance rows in the near set of the point.
pub(super) fn lagrangian_grad(
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

/// Powell-damped BFGS update of `h` with step `s` and gradient change `y`.
pub(super) fn bfgs_update(h: &mut [Vars; MAX_VARS], s: &Vars, y: &Vars, n: usize) {
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
