//! A small dense convex QP solver (primal active set) on fixed-size buffers:
//!
//! minimise ½ pᵀBp + gᵀp  subject to  Aₑ p = 0  and  aᵢᵀp ≥ bᵢ,
//!
//! started from the feasible point p = 0 (the SQP keeps its iterate feasible, so every bᵢ ≤ 0).
//! Each iteration solves the equality-constrained KKT system of the working set by Gaussian
//! elimination with partial pivoting (Nocedal & Wright, Algorithm 16.3).

use crate::optim::linalg::solve;
use crate::optim::problem::{Vars, MAX_VARS};

/// Inequality rows the QP can hold: two bounds per variable, the tilt cone and clearances.
pub const MAX_ROWS: usize = 2 * MAX_VARS + 1 + 12;

/// General (not axis) inequality rows the QP can hold: the tilt cone and the clearances.
const MAX_GENERAL: usize = MAX_ROWS - 2 * MAX_VARS;

const MAX_EQ: usize = 3;
const KKT: usize = MAX_VARS + MAX_EQ + MAX_VARS;

/// A QP instance.
#[derive(Clone, Debug)]
pub struct Qp {
    /// Number of variables.
    pub n: usize,
    /// Hessian (positive definite).
    pub h: [Vars; MAX_VARS],
    /// Linear term.
    pub g: Vars,
    /// Equality rows (`p` must be orthogonal to them).
    pub eq: [Vars; MAX_EQ],
    /// Number of equality rows.
    pub m_eq: usize,
    /// The general inequality rows aᵢ, in the order pushed; axis rows take no room (800 B less
    /// stack under every SQP step on the device).
    general: [Vars; MAX_GENERAL],
    /// Number of general rows.
    m_general: usize,
    /// Row i is ±(unit vector k) when `axis[i]` is ±(k + 1) (a bound: its products are one
    /// element, exactly the dot product's value), general row `axis[i] - i8::MIN` otherwise.
    axis: [i8; MAX_ROWS],
    /// Right-hand sides bᵢ (≤ 0).
    pub rhs: [f32; MAX_ROWS],
    /// Number of inequality rows.
    pub m: usize,
    /// The KKT system's buffer, reused by every solve (every entry a solve reads it writes
    /// first): zeroing kilobytes per solve cost more on the device than some solves.
    kkt: [[f32; KKT]; KKT],
}

/// A QP solution.
#[derive(Clone, Debug)]
pub struct QpSolution {
    /// The step.
    pub p: Vars,
    /// Multipliers of the equality rows.
    pub eq_mult: [f32; MAX_EQ],
    /// Multipliers of the inequality rows (zero for inactive rows).
    pub mult: [f32; MAX_ROWS],
}

/// Why the QP could not be solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QpError {
    /// The KKT matrix of a working set was singular (dependent constraints).
    Singular,
    /// The active-set iteration budget ran out.
    Budget,
}

/// The `axis` code of general row `index`: below every axis code (±1 ..= ±MAX_VARS).
const fn general_code(index: usize) -> i8 {
    (i8::MIN as isize + index as isize) as i8
}

fn is_general(code: i8) -> bool {
    code < -(MAX_VARS as i8)
}

fn general_index(code: i8) -> usize {
    (i16::from(code) - i16::from(i8::MIN)) as usize
}

const _: () = assert!(MAX_GENERAL + MAX_VARS < 128);

impl Qp {
    /// An empty QP over `n` variables with Hessian `h` and gradient `g`.
    pub fn new(n: usize, h: [Vars; MAX_VARS], g: Vars) -> Qp {
        Qp {
            n,
            h,
            g,
            eq: [[0.0; MAX_VARS]; MAX_EQ],
            m_eq: 0,
            general: [[0.0; MAX_VARS]; MAX_GENERAL],
            m_general: 0,
            axis: [0; MAX_ROWS],
            rhs: [0.0; MAX_ROWS],
            m: 0,
            kkt: [[0.0; KKT]; KKT],
        }
    }

    /// Empties the QP and gives it a new gradient, keeping the buffers (rows past the new count
    /// are never read) and the Hessian (the SQP's quasi-Newton matrix lives in the QP): an SQP
    /// iteration reuses one QP instead of building or copying kilobytes afresh.
    pub fn reset_rows(&mut self, n: usize, g: &Vars) {
        self.n = n;
        self.g = *g;
        self.m_eq = 0;
        self.m = 0;
        self.m_general = 0;
    }

    /// Adds an equality row; returns false when full.
    pub fn push_eq(&mut self, a: &Vars) -> bool {
        if self.m_eq >= MAX_EQ {
            return false;
        }
        self.eq[self.m_eq] = *a;
        self.m_eq += 1;
        true
    }

    /// Adds an inequality row aᵀp ≥ b (b is clamped to ≤ 0); returns false when full.
    pub fn push_row(&mut self, a: &Vars, b: f32) -> bool {
        if self.m >= MAX_ROWS || self.m_general >= MAX_GENERAL {
            return false;
        }
        self.general[self.m_general] = *a;
        self.axis[self.m] = general_code(self.m_general);
        self.m_general += 1;
        self.rhs[self.m] = crate::fmath::min(b, 0.0);
        self.m += 1;
        true
    }

    /// Adds the row `sign` · (unit vector `k`) ≥ b (`sign` +1 or -1; b clamped to ≤ 0), the
    /// same constraint as [`Qp::push_row`] of that vector at a fraction of the work; returns
    /// false when full.
    pub fn push_axis(&mut self, k: usize, sign: f32, b: f32) -> bool {
        if self.m >= MAX_ROWS || k >= MAX_VARS {
            return false;
        }
        let code = (k + 1) as i8;
        self.axis[self.m] = if sign < 0.0 { -code } else { code };
        self.rhs[self.m] = crate::fmath::min(b, 0.0);
        self.m += 1;
        true
    }

    /// Solves the QP from p = 0.
    pub fn solve(&mut self) -> Result<QpSolution, QpError> {
        let n = self.n;
        let dot = |a: &Vars, b: &Vars| {
            let mut s = 0.0;
            for k in 0..n {
                s += a[k] * b[k];
            }
            s
        };
        let axis = self.axis;
        // aᵢ · v: for an axis row the one product that is not zero (the sum of the others' ±0
        // does not change it).
        let row_dot = |i: usize, v: &Vars| match axis[i] {
            a if is_general(a) => dot(&self.general[general_index(a)], v),
            a if a > 0 => v[(a - 1) as usize],
            a => -v[(-a - 1) as usize],
        };
        let mut p = [0.0f32; MAX_VARS];
        let mut working = [0usize; MAX_VARS];
        let mut w_len = 0usize;
        let mut in_working = [false; MAX_ROWS];
        // Reused each iteration: every entry of the leading dim × dim block is written below.
        let k = &mut self.kkt;
        let mut rhs = [0.0f32; KKT];
        // The rows do not change during a solve: their norms are taken once.
        let mut row_norms = [0.0f32; MAX_ROWS];
        for (i, norm) in row_norms.iter_mut().enumerate().take(self.m) {
            *norm = if is_general(axis[i]) {
                let a = &self.general[general_index(axis[i])];
                crate::fmath::sqrt(dot(a, a))
            } else {
                1.0
            };
        }
        for _ in 0..4 * MAX_ROWS {
            // KKT system: [H  -Aᵀ; A 0] [d; μ] = [-(Hp + g); 0]
            let dim = n + self.m_eq + w_len;
            for row in k.iter_mut().take(dim).skip(n) {
                for v in row.iter_mut().take(dim).skip(n) {
                    *v = 0.0;
                }
            }
            rhs[n..dim].iter_mut().for_each(|r| *r = 0.0);
            for i in 0..n {
                for j in 0..n {
                    k[i][j] = self.h[i][j];
                }
                let mut hp = 0.0;
                for j in 0..n {
                    hp += self.h[i][j] * p[j];
                }
                rhs[i] = -(hp + self.g[i]);
            }
            for r in 0..self.m_eq + w_len {
                let code = if r < self.m_eq {
                    general_code(0)
                } else {
                    axis[working[r - self.m_eq]]
                };
                if is_general(code) {
                    let a = if r < self.m_eq {
                        &self.eq[r]
                    } else {
                        &self.general[general_index(code)]
                    };
                    for j in 0..n {
                        k[n + r][j] = a[j];
                        k[j][n + r] = -a[j];
                    }
                } else {
                    let at = (code.unsigned_abs() - 1) as usize;
                    let one = if code > 0 { 1.0f32 } else { -1.0 };
                    for j in 0..n {
                        let a = if j == at { one } else { 0.0 };
                        k[n + r][j] = a;
                        k[j][n + r] = -a;
                    }
                }
            }
            if !solve(k, &mut rhs, dim) {
                return Err(QpError::Singular);
            }
            let sol = &rhs;
            let d = &sol[..n];

            let step_norm = d
                .iter()
                .fold(0.0f32, |m, v| crate::fmath::max(m, libm::fabsf(*v)));
            let scale = p
                .iter()
                .take(n)
                .fold(1.0f32, |m, v| crate::fmath::max(m, libm::fabsf(*v)));
            if step_norm > 1e-7 * scale {
                // Longest step along d that keeps every inequality.
                let mut alpha = 1.0f32;
                let mut blocking = None;
                let mut dv = [0.0f32; MAX_VARS];
                dv[..n].copy_from_slice(d);
                let d_norm = crate::fmath::sqrt(dot(&dv, &dv));
                for i in 0..self.m {
                    if in_working[i] {
                        continue;
                    }
                    let ad = row_dot(i, &dv);
                    // Rounding makes a just-released or parallel row look blocking by a hair; only
                    // a row that the step really crosses may block (this prevents cycling).
                    let row_norm = row_norms[i];
                    if ad < -1e-5 * row_norm * d_norm {
                        let slack = self.rhs[i] - row_dot(i, &p);
                        let t = crate::fmath::max(slack / ad, 0.0);
                        if t < alpha {
                            alpha = t;
                            blocking = Some(i);
                        }
                    }
                }
                for j in 0..n {
                    p[j] += alpha * dv[j];
                }
                if let Some(i) = blocking {
                    if w_len < n {
                        working[w_len] = i;
                        w_len += 1;
                        in_working[i] = true;
                        continue;
                    }
                    return Err(QpError::Singular);
                }
                // A full, unblocked step: p now minimises over the working set, and the
                // multipliers of this solve are the minimiser's (the KKT system is linear in p),
                // so no second solve is needed to read them.
            }
            // Stationary on the working set: check the inequality multipliers.
            let mut worst: Option<(usize, f32)> = None;
            for w in 0..w_len {
                let mu = sol[n + self.m_eq + w];
                if mu < 0.0 && worst.is_none_or(|(_, m)| mu < m) {
                    worst = Some((w, mu));
                }
            }
            match worst {
                None => {
                    let mut out = QpSolution {
                        p,
                        eq_mult: [0.0; MAX_EQ],
                        mult: [0.0; MAX_ROWS],
                    };
                    out.eq_mult[..self.m_eq].copy_from_slice(&sol[n..n + self.m_eq]);
                    for w in 0..w_len {
                        out.mult[working[w]] = sol[n + self.m_eq + w];
                    }
                    return Ok(out);
                }
                Some((w, _)) => {
                    in_working[working[w]] = false;
                    for i in w..w_len - 1 {
                        working[i] = working[i + 1];
                    }
                    w_len -= 1;
                }
            }
        }
        Err(QpError::Budget)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity(n: usize) -> [Vars; MAX_VARS] {
        let mut h = [[0.0; MAX_VARS]; MAX_VARS];
        for (i, row) in h.iter_mut().enumerate().take(n) {
            row[i] = 1.0;
        }
        h
    }

    #[test]
    fn unconstrained_step_is_newton() {
        let mut g = [0.0; MAX_VARS];
        g[0] = 2.0;
        g[1] = -4.0;
        let s = Qp::new(2, identity(2), g).solve().unwrap();
        assert!((s.p[0] + 2.0).abs() < 1e-6 && (s.p[1] - 4.0).abs() < 1e-6);
    }

    #[test]
    fn bound_and_equality_are_respected() {
        // min ½|p|² + g·p with g = (-1, -1, 0), p0 + p1 + p2 = 0, p0 ≤ 0.25.
        let mut g = [0.0; MAX_VARS];
        g[0] = -1.0;
        g[1] = -1.0;
        let mut qp = Qp::new(3, identity(3), g);
        let mut eq = [0.0; MAX_VARS];
        eq[..3].copy_from_slice(&[1.0, 1.0, 1.0]);
        qp.push_eq(&eq);
        let mut row = [0.0; MAX_VARS];
        row[0] = -1.0;
        qp.push_row(&row, -0.25);
        let s = qp.solve().unwrap();
        // Without the bound: p = (1/3, 1/3, -2/3); with it p0 = 0.25 and p1 - p2 = 1 - ... :
        // minimise over p1: ½(p1² + (0.25 + p1)²) - p1 -> p1 = 0.375, p2 = -0.625.
        assert!((s.p[0] - 0.25).abs() < 1e-5, "{:?}", &s.p[..3]);
        assert!((s.p[1] - 0.375).abs() < 1e-5);
        assert!((s.p[2] + 0.625).abs() < 1e-5);
        assert!(s.mult[0] > 0.0);
    }
}
