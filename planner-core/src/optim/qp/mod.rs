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

/// What an inequality row aᵢ is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Row {
    /// +(unit vector k): a lower bound on pₖ. Its products are one element, exactly the dot
    /// product's value, and it takes no room in `general`.
    Plus(u8),
    /// −(unit vector k): an upper bound on pₖ.
    Minus(u8),
    /// General row `general[i]`.
    General(u8),
}

/// The coefficients of one constraint row of the KKT system.
enum Coefficients<'a> {
    /// A general row.
    Dense(&'a Vars),
    /// `sign` times unit vector `k` (`Unit(k, sign)`).
    Unit(usize, f32),
}

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
    /// What each inequality row is.
    rows: [Row; MAX_ROWS],
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
#[non_exhaustive]
pub enum QpError {
    /// The KKT matrix of a working set was singular: dependent constraints, or a Hessian without
    /// curvature along a direction the working set leaves free (the QP does not follow a
    /// direction of unbounded descent to the box; it reports it).
    Singular,
    /// The active-set iteration budget ran out.
    Budget,
}

impl QpSolution {
    /// All zero: a buffer for [`Qp::solve_into`].
    pub fn empty() -> Self {
        QpSolution {
            p: [0.0; MAX_VARS],
            eq_mult: [0.0; MAX_EQ],
            mult: [0.0; MAX_ROWS],
        }
    }
}

impl core::fmt::Display for QpError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            QpError::Singular => "the QP's KKT system is singular",
            QpError::Budget => "the QP's active-set iterations ran out",
        })
    }
}

impl core::error::Error for QpError {}

const _: () = assert!(MAX_GENERAL < 256 && MAX_VARS < 256);

/// The working set of an active-set solve: indices of inequality rows held as equalities.
struct Working {
    rows: [usize; MAX_VARS],
    len: usize,
    holds: [bool; MAX_ROWS],
}

impl Working {
    fn empty() -> Self {
        Working {
            rows: [0; MAX_VARS],
            len: 0,
            holds: [false; MAX_ROWS],
        }
    }

    fn add(&mut self, row: usize) {
        self.rows[self.len] = row;
        self.len += 1;
        self.holds[row] = true;
    }

    /// Drops the `w`-th member, keeping the order of the others.
    fn drop_at(&mut self, w: usize) {
        self.holds[self.rows[w]] = false;
        for i in w..self.len - 1 {
            self.rows[i] = self.rows[i + 1];
        }
        self.len -= 1;
    }
}

/// The first `n` elements of `a` · `b`.
fn dot(a: &Vars, b: &Vars, n: usize) -> f32 {
    let mut s = 0.0;
    for k in 0..n {
        s += a[k] * b[k];
    }
    s
}

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
            rows: [Row::Plus(0); MAX_ROWS],
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
        self.rows[self.m] = Row::General(self.m_general as u8);
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
        self.rows[self.m] = if sign < 0.0 {
            Row::Minus(k as u8)
        } else {
            Row::Plus(k as u8)
        };
        self.rhs[self.m] = crate::fmath::min(b, 0.0);
        self.m += 1;
        true
    }

    /// aᵢ · v: for an axis row the one product that is not zero (the sum of the others' ±0 does
    /// not change it).
    #[inline]
    fn row_dot(&self, i: usize, v: &Vars) -> f32 {
        match self.rows[i] {
            Row::General(g) => dot(&self.general[usize::from(g)], v, self.n),
            Row::Plus(k) => v[usize::from(k)],
            Row::Minus(k) => -v[usize::from(k)],
        }
    }

    /// ‖aᵢ‖ of every row (they do not change during a solve).
    fn row_norms(&self) -> [f32; MAX_ROWS] {
        let mut norms = [0.0f32; MAX_ROWS];
        for (i, norm) in norms.iter_mut().enumerate().take(self.m) {
            *norm = match self.rows[i] {
                Row::General(g) => {
                    let a = &self.general[usize::from(g)];
                    crate::fmath::sqrt(dot(a, a, self.n))
                }
                Row::Plus(_) | Row::Minus(_) => 1.0,
            };
        }
        norms
    }

    /// Writes the KKT system of the working set at `p` into `self.kkt` and `rhs`:
    /// [H  -Aᵀ; A 0] [d; μ] = [-(Hp + g); 0], the equality rows first. Returns its dimension.
    fn assemble(&mut self, p: &Vars, working: &Working, rhs: &mut [f32; KKT]) -> usize {
        let n = self.n;
        let dim = n + self.m_eq + working.len;
        let k = &mut self.kkt;
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
        for r in 0..self.m_eq + working.len {
            let coefficients = if r < self.m_eq {
                Coefficients::Dense(&self.eq[r])
            } else {
                match self.rows[working.rows[r - self.m_eq]] {
                    Row::General(g) => Coefficients::Dense(&self.general[usize::from(g)]),
                    Row::Plus(at) => Coefficients::Unit(usize::from(at), 1.0),
                    Row::Minus(at) => Coefficients::Unit(usize::from(at), -1.0),
                }
            };
            // Row n + r holds the constraint, column n + r its negation (the -Aᵀ block).
            match coefficients {
                Coefficients::Dense(a) => {
                    for j in 0..n {
                        k[n + r][j] = a[j];
                        k[j][n + r] = -a[j];
                    }
                }
                Coefficients::Unit(at, sign) => {
                    for j in 0..n {
                        let a = if j == at { sign } else { 0.0 };
                        k[n + r][j] = a;
                        k[j][n + r] = -a;
                    }
                }
            }
        }
        dim
    }

    /// Moves `p` along `d` as far as every row outside the working set allows (at most the full
    /// step); returns the row that blocked it, if one did.
    fn advance(
        &self,
        p: &mut Vars,
        d: &[f32],
        working: &Working,
        row_norms: &[f32; MAX_ROWS],
    ) -> Option<usize> {
        let n = self.n;
        let mut alpha = 1.0f32;
        let mut blocking = None;
        let mut dv = [0.0f32; MAX_VARS];
        dv[..n].copy_from_slice(d);
        let d_norm = crate::fmath::sqrt(dot(&dv, &dv, n));
        for i in 0..self.m {
            if working.holds[i] {
                continue;
            }
            let ad = self.row_dot(i, &dv);
            // Rounding makes a just-released or parallel row look blocking by a hair; only a row
            // that the step really crosses may block (this prevents cycling).
            if ad < -1e-5 * row_norms[i] * d_norm {
                let slack = self.rhs[i] - self.row_dot(i, p);
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
        blocking
    }

    /// Writes into `out` the solution at `p` with the multipliers `sol` of the working set's KKT
    /// system.
    fn write_solution(&self, p: &Vars, working: &Working, sol: &[f32; KKT], out: &mut QpSolution) {
        let n = self.n;
        out.p = *p;
        out.eq_mult = [0.0; MAX_EQ];
        out.mult = [0.0; MAX_ROWS];
        out.eq_mult[..self.m_eq].copy_from_slice(&sol[n..n + self.m_eq]);
        for w in 0..working.len {
            out.mult[working.rows[w]] = sol[n + self.m_eq + w];
        }
    }

    /// Solves the QP from p = 0.
    pub fn solve(&mut self) -> Result<QpSolution, QpError> {
        let mut out = QpSolution::empty();
        self.solve_into(&mut out).map(|()| out)
    }

    /// [`Qp::solve`] into `out` (left as it was on `Err`): a caller that keeps the solution
    /// saves moving it out of a `Result`, which the device pays for in every SQP step.
    pub fn solve_into(&mut self, out: &mut QpSolution) -> Result<(), QpError> {
        let n = self.n;
        let mut p = [0.0f32; MAX_VARS];
        let mut working = Working::empty();
        // Reused each iteration: every entry of the leading dim × dim block is written.
        let mut rhs = [0.0f32; KKT];
        let row_norms = self.row_norms();
        for _ in 0..4 * MAX_ROWS {
            let dim = self.assemble(&p, &working, &mut rhs);
            if !solve(&mut self.kkt, &mut rhs, dim) {
                return Err(QpError::Singular);
            }
            let d = &rhs[..n];
            let step_norm = d
                .iter()
                .fold(0.0f32, |m, v| crate::fmath::max(m, libm::fabsf(*v)));
            let scale = p
                .iter()
                .take(n)
                .fold(1.0f32, |m, v| crate::fmath::max(m, libm::fabsf(*v)));
            if step_norm > 1e-7 * scale {
                if let Some(i) = self.advance(&mut p, d, &working, &row_norms) {
                    if working.len < n {
                        working.add(i);
                        continue;
                    }
                    return Err(QpError::Singular);
                }
                // A full, unblocked step: p now minimises over the working set, and the
                // multipliers of this solve are the minimiser's (the KKT system is linear in p),
                // so no second solve is needed to read them.
            }
            // Stationary on the working set: the most negative inequality multiplier, if any,
            // leaves it.
            let mut worst: Option<(usize, f32)> = None;
            for w in 0..working.len {
                let mu = rhs[n + self.m_eq + w];
                if mu < 0.0 && worst.is_none_or(|(_, m)| mu < m) {
                    worst = Some((w, mu));
                }
            }
            match worst {
                None => {
                    self.write_solution(&p, &working, &rhs, out);
                    return Ok(());
                }
                Some((w, _)) => working.drop_at(w),
            }
        }
        Err(QpError::Budget)
    }
}

#[cfg(test)]
mod tests;
