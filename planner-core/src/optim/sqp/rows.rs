//! The QP of one SQP step: which rows it holds and how they are built.

use super::{QP_CLEARANCES, TRUST};
use crate::optim::objective::{Derivatives, Value, MAX_NEAR};
use crate::optim::problem::{Problem, Vars};
use crate::optim::qp::Qp;

/// Which QP rows hold which constraint (for their multipliers).
pub(super) struct QpRows {
    /// Row of the first variable's lower bound: variable k's lower and upper bounds (each within
    /// the trust box) are rows `bounds + 2k` and `bounds + 2k + 1`.
    pub bounds: usize,
    /// (obstacle, row) of each clearance row (the obstacle's index, not its slot: the rows
    /// outlive the near set of the point they were built at).
    pub clearances: [(usize, usize); QP_CLEARANCES],
    /// Clearance rows held.
    pub n_clear: usize,
    /// Row of the tilt cone (3-D plans from the entry only).
    pub tilt: usize,
}

impl QpRows {
    /// No rows: a buffer for [`tangent_qp`].
    pub(super) fn empty() -> Self {
        QpRows {
            bounds: 0,
            clearances: [(0, 0); QP_CLEARANCES],
            n_clear: 0,
            tilt: 0,
        }
    }
}

/// The QP of the tangent step at `cur`: bounds within the trust box, the tilt cone (3-D) and the
/// `clear_limit` nearest clearances, linearised; the Hessian is the one in `qp`. Which rows are
/// which is written into `rows`.
pub(super) fn tangent_qp(
    qp: &mut Qp,
    p: &Problem,
    cur: &Value,
    cur_d: &Derivatives,
    clear_limit: usize,
    rows: &mut QpRows,
) {
    qp.reset_rows(p.n, &cur_d.grad);
    rows.bounds = qp.m;
    rows.n_clear = 0;
    rows.tilt = push_step_limits(qp, p, &cur.x, cur_d);
    push_nearest_clearances(
        qp,
        p,
        cur,
        cur_d,
        clear_limit,
        |_| true,
        |slot, row| {
            rows.clearances[rows.n_clear] = (usize::from(cur.near[slot]), row);
            rows.n_clear += 1;
        },
    );
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

/// Pushes the linearised clearances (kept at the floor) of up to `limit` obstacles of the near
/// set of `cur` whose slot `eligible` holds for, nearest first (the first slot of equals);
/// `pushed(slot, row)` is told each row.
pub(crate) fn push_nearest_clearances(
    qp: &mut Qp,
    p: &Problem,
    cur: &Value,
    d: &Derivatives,
    limit: usize,
    eligible: impl Fn(usize) -> bool,
    mut pushed: impl FnMut(usize, usize),
) {
    let obstacles = cur.near_count.min(MAX_NEAR);
    let mut taken = [false; MAX_NEAR];
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
