//! Restoration: moving a point onto the target manifold (end point = target) while keeping the
//! bounds. Every SQP iterate and trial point is restored, so the SQP's merit function is the
//! objective itself.

use super::{MAX_RESTORE, TRUST};
use crate::optim::linalg;
use crate::optim::problem::{Problem, Vars, MAX_VARS};

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
