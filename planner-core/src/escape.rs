//! Moving a near miss out of the obstacles it touches.
//!
//! A seed whose path cuts into an obstacle by a few millimetres may sit next to a feasible region
//! far thinner than the sweep's spacing (a passage between two obstacles a tenth of a millimetre
//! wide). Gauss–Newton steps on the violated clearances, taken along the target manifold and with
//! every other clearance held at the floor, walk into such a region when it is there.

use crate::problem::{Problem, Vars, MAX_VARS};
use crate::qp::Qp;
use crate::scenario::MAX_OBSTACLES;
use crate::sqp::{restore, QP_CLEARANCES, TRUST};

/// Gauss–Newton steps tried.
const MAX_STEPS: u32 = 8;
/// Clearance aimed at above the floor (mm): a little room so that rounding keeps the result clear.
const MARGIN: f32 = 0.02;

/// Total depth of the clearances below the floor (zero when none is).
fn violation(p: &Problem, clearance: &[f32]) -> f32 {
    clearance
        .iter()
        .map(|c| (p.min_clearance - c).max(0.0))
        .sum()
}

/// From `x0` (on the target or near it), a point on the target that keeps every clearance and
/// bound, if the steps find one. `evals` counts evaluations.
pub fn escape(p: &Problem, x0: &Vars, evals: &mut u32) -> Option<Vars> {
    let mut x = *x0;
    if !restore(p, &mut x, evals) {
        return None;
    }
    let n = p.n;
    let obstacles = p.scenario.obstacles.len();
    let mut cur = p.value(&x);
    *evals += 1;
    for _ in 0..MAX_STEPS {
        if cur.admissible(p) {
            return Some(cur.x);
        }
        let depth = violation(p, &cur.clearance[..obstacles]);
        let d = p.derivatives(&cur);
        // Least squares on the violated clearances: H = sum g gᵀ (+ a small ridge), g = sum r g.
        let mut h = [[0.0f32; MAX_VARS]; MAX_VARS];
        let mut grad = [0.0f32; MAX_VARS];
        let goal = p.min_clearance + MARGIN;
        for o in 0..obstacles {
            let r = cur.clearance[o] - goal;
            if r >= 0.0 {
                continue;
            }
            let g = &d.clearance_grad[o];
            for i in 0..n {
                grad[i] += r * g[i];
                for j in 0..n {
                    h[i][j] += g[i] * g[j];
                }
            }
        }
        let trace: f32 = (0..n).map(|i| h[i][i]).sum();
        for (i, row) in h.iter_mut().enumerate().take(n) {
            row[i] += 1e-3 * trace + 1e-6;
        }
        let mut qp = Qp::new(n, h, grad);
        for r in 0..p.m_eq {
            qp.push_eq(&d.jac[r]);
        }
        for k in 0..n {
            let mut unit = [0.0; MAX_VARS];
            unit[k] = 1.0;
            qp.push_row(&unit, (p.lower[k] - cur.x[k]).max(-TRUST));
            unit[k] = -1.0;
            qp.push_row(&unit, -(p.upper[k] - cur.x[k]).min(TRUST));
        }
        if !p.plane {
            qp.push_row(&p.tilt_margin_grad(&cur.x), -p.tilt_margin(&cur.x));
        }
        // The clear obstacles nearest to the floor stay clear (to first order).
        let mut taken = [false; MAX_OBSTACLES];
        for _ in 0..QP_CLEARANCES.min(obstacles) {
            let nearest = (0..obstacles)
                .filter(|&o| !taken[o] && cur.clearance[o] > p.min_clearance)
                .min_by(|&a, &b| cur.clearance[a].total_cmp(&cur.clearance[b]));
            let Some(o) = nearest else { break };
            taken[o] = true;
            qp.push_row(&d.clearance_grad[o], p.min_clearance - cur.clearance[o]);
        }
        let step = qp.solve().ok()?;
        // Halve the step until the violation shrinks.
        let mut t = 1.0f32;
        let mut next = None;
        for _ in 0..4 {
            let mut xt = cur.x;
            for k in 0..n {
                xt[k] = (cur.x[k] + t * step.p[k]).clamp(p.lower[k], p.upper[k]);
            }
            if restore(p, &mut xt, evals) {
                let v = p.value(&xt);
                *evals += 1;
                if violation(p, &v.clearance[..obstacles]) < depth && p.tilt_margin(&xt) >= 0.0 {
                    next = Some(v);
                    break;
                }
            }
            t *= 0.5;
        }
        cur = next?;
    }
    cur.admissible(p).then_some(cur.x)
}
