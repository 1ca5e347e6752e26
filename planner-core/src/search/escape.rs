//! Moving a near miss out of the obstacles it touches.
//!
//! A seed whose path cuts into an obstacle by a few millimetres may sit next to a feasible region
//! far thinner than the sweep's spacing (a passage between two obstacles a tenth of a millimetre
//! wide). Gauss–Newton steps on the violated clearances, taken along the target manifold and with
//! every other clearance held at the floor, walk into such a region when it is there.

use crate::optim::objective::Value;
use crate::optim::problem::{Problem, Vars, MAX_VARS};
use crate::optim::qp::Qp;
use crate::optim::sqp::{push_nearest_clearances, push_step_limits, restore, QP_CLEARANCES};

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
/// bound, with its value, if the steps find one. `evals` counts evaluations.
#[inline(never)] // Its buffers need not share the stack with the SQP's.
pub fn escape(p: &Problem, x0: &Vars, evals: &mut u32) -> Option<Value> {
    let mut x = *x0;
    if !restore(p, &mut x, evals) {
        return None;
    }
    let n = p.n;
    let mut cur = p.value(&x);
    *evals += 1;
    for _ in 0..MAX_STEPS {
        if cur.admissible(p) {
            return Some(cur);
        }
        // Over the near set: the obstacles cut into are the nearest ones.
        let depth = violation(p, &cur.clearance[..cur.near_count]);
        let d = p.derivatives(&cur);
        // Least squares on the violated clearances: H = sum g gᵀ (+ a small ridge), g = sum r g.
        let mut h = [[0.0f32; MAX_VARS]; MAX_VARS];
        let mut grad = [0.0f32; MAX_VARS];
        let goal = p.min_clearance + MARGIN;
        for o in 0..cur.near_count {
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
        push_step_limits(&mut qp, p, &cur.x, &d);
        // The clear obstacles nearest to the floor stay clear (to first order).
        let clear = |o: usize| cur.clearance[o] > p.min_clearance;
        push_nearest_clearances(&mut qp, p, &cur, &d, QP_CLEARANCES, clear, |_, _| {});
        let step = qp.solve().ok()?;
        // Halve the step until the violation shrinks.
        let mut t = 1.0f32;
        let mut next = None;
        for _ in 0..4 {
            let mut xt = cur.x;
            for k in 0..n {
                xt[k] = crate::fmath::clamp(cur.x[k] + t * step.p[k], p.lower[k], p.upper[k]);
            }
            if restore(p, &mut xt, evals) {
                let v = p.value(&xt);
                *evals += 1;
                if violation(p, &v.clearance[..v.near_count]) < depth && p.tilt_margin(&xt) >= 0.0 {
                    next = Some(v);
                    break;
                }
            }
            t *= 0.5;
        }
        cur = next?;
    }
    cur.admissible(p).then_some(cur)
}
