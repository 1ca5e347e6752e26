//! Global search over a variant's free parameters: a dense grid (plane mode) or many random
//! samples (3-D), then Nelder-Mead from the best distinct starts. The end stays exactly on the
//! target throughout because the last two segments are solved in closed form.

use super::problem::{score, Cand, Problem, INFEASIBLE};
use super::variant::{Var, Variant};
use core::f64::consts::PI;
use needle_sim::random::{seeded, Draw};

/// How hard to search; 1.0 is the default suite's effort.
#[derive(Clone, Copy, Debug)]
pub struct Effort(pub f64);

/// The best path found for one variant.
#[derive(Clone, Copy, Debug)]
pub struct Found {
    /// F.
    pub objective: f64,
    /// The path.
    pub cand: Cand,
}

struct Objective<'a> {
    pb: &'a Problem,
    variant: &'a Variant,
    vars: Vec<Var>,
    buf: Vec<Cand>,
    best: Option<Found>,
    evaluations: u64,
}

impl Objective<'_> {
    /// Puts `x` inside the box and the tilt cone; returns how far it had to move.
    fn project(&self, x: &mut [f64]) -> f64 {
        let mut moved = 0.0;
        let tilt = self.pb.max_tilt;
        for (xi, v) in x.iter_mut().zip(&self.vars) {
            let (lo, hi) = match *v {
                Var::Theta1 | Var::Theta2 => (-tilt, tilt),
                Var::Length(max) => (0.0, max),
                Var::Roll => {
                    *xi = super::frame::wrap(*xi);
                    continue;
                }
            };
            let c = xi.clamp(lo, hi);
            moved += (c - *xi).abs();
            *xi = c;
        }
        if let (Some(i1), Some(i2)) = (
            self.vars.iter().position(|v| *v == Var::Theta1),
            self.vars.iter().position(|v| *v == Var::Theta2),
        ) {
            let (a, b) = (x[i1], x[i2]);
            if a.cos() * b.cos() < tilt.cos() {
                // Shrink towards the axis onto the cone's boundary.
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..60 {
                    let m = 0.5 * (lo + hi);
                    if (m * a).cos() * (m * b).cos() >= tilt.cos() {
                        lo = m;
                    } else {
                        hi = m;
                    }
                }
                x[i1] = lo * a;
                x[i2] = lo * b;
                moved += (1.0 - lo) * (a.abs() + b.abs());
            }
        }
        moved
    }

    fn value(&mut self, x: &[f64]) -> f64 {
        let mut y = x.to_vec();
        let moved = self.project(&mut y);
        self.evaluations += 1;
        let mut buf = core::mem::take(&mut self.buf);
        self.variant.candidates(self.pb, &y, &mut buf);
        let mut best = f64::INFINITY;
        for c in &buf {
            let f = score(self.pb, c, self.variant.control);
            if f < best {
                best = f;
            }
            if f < INFEASIBLE && f < self.best.map_or(f64::INFINITY, |b| b.objective) {
                self.best = Some(Found {
                    objective: f,
                    cand: *c,
                });
            }
        }
        self.buf = buf;
        best + 1e3 * moved
    }
}

/// Nelder-Mead from `x0` with initial steps `step`; returns the best point and value.
fn nelder_mead(obj: &mut Objective, x0: &[f64], step: &[f64], iters: usize) -> (Vec<f64>, f64) {
    let n = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    simplex.push((x0.to_vec(), obj.value(x0)));
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] += step[i];
        let f = obj.value(&x);
        simplex.push((x, f));
    }
    let nf = n as f64;
    // Adaptive coefficients (Gao and Han) behave better in a few dimensions too.
    let (alpha, beta, gamma, delta) = (
        1.0,
        1.0 + 2.0 / nf,
        0.75 - 1.0 / (2.0 * nf),
        1.0 - 1.0 / nf.max(2.0),
    );
    for _ in 0..iters {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (fbest, fworst) = (simplex[0].1, simplex[n].1);
        let size = simplex[1..]
            .iter()
            .map(|(x, _)| {
                x.iter()
                    .zip(&simplex[0].0)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        if fbest.is_finite()
            && (fworst - fbest).abs() <= 1e-12 * (1.0 + fbest.abs())
            && size < 1e-10
        {
            break;
        }
        if size < 1e-13 {
            break;
        }
        let mut centroid = vec![0.0; n];
        for (x, _) in &simplex[..n] {
            for (c, xi) in centroid.iter_mut().zip(x) {
                *c += xi / nf;
            }
        }
        let along = |t: f64| -> Vec<f64> {
            centroid
                .iter()
                .zip(&simplex[n].0)
                .map(|(c, w)| c + t * (c - w))
                .collect()
        };
        let xr = along(alpha);
        let fr = obj.value(&xr);
        if fr < simplex[0].1 {
            let xe = along(alpha * beta);
            let fe = obj.value(&xe);
            simplex[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[n - 1].1 {
            simplex[n] = (xr, fr);
        } else {
            let outside = fr < simplex[n].1;
            let xc = along(if outside { alpha * gamma } else { -gamma });
            let fc = obj.value(&xc);
            if (outside && fc <= fr) || (!outside && fc < simplex[n].1) {
                simplex[n] = (xc, fc);
            } else {
                let x0 = simplex[0].0.clone();
                for v in simplex.iter_mut().skip(1) {
                    let x: Vec<f64> = x0
                        .iter()
                        .zip(&v.0)
                        .map(|(b, w)| b + delta * (w - b))
                        .collect();
                    let f = obj.value(&x);
                    *v = (x, f);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex.swap_remove(0)
}

/// Polishes a start: Nelder-Mead, then restarts with shrinking steps around the best point.
fn polish(obj: &mut Objective, x0: &[f64], step: &[f64]) -> f64 {
    let n = x0.len();
    let mut x = x0.to_vec();
    let mut f = f64::INFINITY;
    let mut s = step.to_vec();
    for round in 0..4 {
        let (xn, fn_) = nelder_mead(obj, &x, &s, 300 * n + 200);
        if fn_ <= f {
            x = xn;
            f = fn_;
        }
        let shrink = if round == 0 { 0.3 } else { 0.1 };
        s.iter_mut().for_each(|v| *v *= shrink);
    }
    f
}

fn var_span(v: Var, pb: &Problem) -> (f64, f64) {
    match v {
        Var::Theta1 | Var::Theta2 => (-pb.max_tilt, pb.max_tilt),
        Var::Roll => (-PI, PI),
        Var::Length(max) => (0.0, max),
    }
}

/// Searches one variant; `None` when no feasible path was found.
pub fn search(pb: &Problem, variant: &Variant, effort: Effort, seed: u64) -> (Option<Found>, u64) {
    let vars = variant.vars(pb);
    let mut obj = Objective {
        pb,
        variant,
        vars: vars.clone(),
        buf: Vec::new(),
        best: None,
        evaluations: 0,
    };
    let dim = vars.len();
    if dim == 0 {
        obj.value(&[]);
        return (obj.best, obj.evaluations);
    }
    let spans: Vec<(f64, f64)> = vars.iter().map(|&v| var_span(v, pb)).collect();
    // Sample: a full grid in plane mode (and for one parameter), random points otherwise.
    let mut samples: Vec<(Vec<f64>, f64)> = Vec::new();
    let step: Vec<f64>;
    if pb.plane || dim == 1 {
        let per_dim = match dim {
            1 => (2000.0 * effort.0) as usize,
            2 => (220.0 * effort.0.sqrt()) as usize,
            _ => (50.0 * effort.0.cbrt()) as usize,
        }
        .max(8);
        step = spans
            .iter()
            .map(|(lo, hi)| (hi - lo) / per_dim as f64)
            .collect();
        let count = (per_dim + 1).pow(dim as u32);
        for k in 0..count {
            let mut r = k;
            let mut x = vec![0.0; dim];
            for (d, xi) in x.iter_mut().enumerate() {
                let idx = r % (per_dim + 1);
                r /= per_dim + 1;
                let (lo, hi) = spans[d];
                *xi = lo + (hi - lo) * idx as f64 / per_dim as f64;
            }
            let f = obj.value(&x);
            samples.push((x, f));
        }
    } else {
        let count = (effort.0
            * match dim {
                2 => 6_000.0,
                3 => 20_000.0,
                4 => 40_000.0,
                _ => 60_000.0,
            }) as usize;
        let mut rng = seeded(seed);
        for _ in 0..count {
            let x: Vec<f64> = spans.iter().map(|&(lo, hi)| rng.range(lo, hi)).collect();
            let f = obj.value(&x);
            samples.push((x, f));
        }
        step = spans.iter().map(|(lo, hi)| (hi - lo) * 0.03).collect();
    }
    samples.retain(|s| s.1.is_finite());
    samples.sort_by(|a, b| a.1.total_cmp(&b.1));
    // Distinct starts: the best feasible samples, then the least infeasible ones (a thin
    // feasible region between samples shows as a shallow violation there).
    let starts = (12.0 * effort.0.max(1.0)) as usize;
    let mut chosen: Vec<Vec<f64>> = Vec::new();
    let pick = |want_feasible: bool, limit: usize, chosen: &mut Vec<Vec<f64>>| {
        let mut taken = 0;
        for (x, f) in &samples {
            if taken >= limit {
                break;
            }
            if (*f < INFEASIBLE) != want_feasible {
                continue;
            }
            let near = chosen.iter().any(|c| {
                c.iter()
                    .zip(x)
                    .zip(&step)
                    .zip(&vars)
                    .all(|(((a, b), s), v)| {
                        let d = if *v == Var::Roll {
                            super::frame::wrap(a - b)
                        } else {
                            a - b
                        };
                        d.abs() <= 2.0 * s
                    })
            });
            if !near {
                chosen.push(x.clone());
                taken += 1;
            }
        }
    };
    pick(true, starts, &mut chosen);
    pick(false, starts / 2, &mut chosen);
    for x in chosen {
        polish(&mut obj, &x, &step);
    }
    (obj.best, obj.evaluations)
}
