//! The objective F = a1 L + a2 D + a4 N and the clearances of one form's problem at a point, and
//! their exact first derivatives (every parameter moves the downstream path as a rigid screw).

use super::problem::{v3, Problem, Vars, MAX_VARS};
use crate::model::clearance::{closest_drawn, Closest, Nearest};
use crate::model::kinematics::{PathGeometry, V3};
use crate::model::scenario::{RiskMeasure, MAX_OBSTACLES};

/// The objective and the clearances at one point (no derivatives: what seeds and line searches
/// need).
#[derive(Clone, Debug)]
pub struct Value {
    /// The variables.
    pub x: Vars,
    /// The path.
    pub geo: PathGeometry,
    /// a1 L + a2 D + a4 N (H left out: it is zero wherever the optimiser may go).
    pub objective: f32,
    /// Clearance d_i to each obstacle (mm).
    pub clearance: [f32; MAX_OBSTACLES],
    /// The segment nearest to each obstacle.
    pub nearest_segment: [u8; MAX_OBSTACLES],
    /// Smallest clearance.
    pub min_clearance: f32,
}

impl Value {
    /// Every clearance above the floor and the tilt within its bound.
    pub fn admissible(&self, p: &Problem) -> bool {
        self.min_clearance > p.min_clearance
            && self.objective.is_finite()
            && p.tilt_margin(&self.x) >= 0.0
    }
}

/// First derivatives at a point (what an accepted SQP iterate needs).
#[derive(Clone, Debug)]
pub struct Derivatives {
    /// End point minus target, in the constraint rows' coordinates.
    pub residual: [f32; 3],
    /// Jacobian of `residual`.
    pub jac: [Vars; 3],
    /// Gradient of the objective.
    pub grad: Vars,
    /// Gradient of each clearance.
    pub clearance_grad: [Vars; MAX_OBSTACLES],
}

impl Problem<'_> {
    /// Objective and clearances at `x`.
    pub fn value(&self, x: &Vars) -> Value {
        self.value_or_blocked(x, false)
    }

    /// Like [`Problem::value`], but with `stop_when_blocked` the scan of the obstacles stops at the
    /// first one the path touches (the value is then inadmissible and only `min_clearance` is
    /// meaningful): a sweep over many seeds needs no more.
    pub fn value_or_blocked(&self, x: &Vars, stop_when_blocked: bool) -> Value {
        let mut clearance = [f32::INFINITY; MAX_OBSTACLES];
        let mut nearest_segment = [0u8; MAX_OBSTACLES];
        let geo = self.geometry(x);
        let (objective, min_clearance) = self.objective_of(
            &geo,
            stop_when_blocked,
            &mut clearance,
            &mut nearest_segment,
        );
        Value {
            x: *x,
            geo,
            objective,
            clearance,
            nearest_segment,
            min_clearance,
        }
    }

    /// [`Problem::value`] written into `out` when `out.geo` already holds the path of `x` (a
    /// line search reuses one buffer, and the restoration has just drawn the path: on the
    /// device, moving a `Value` costs more than many of the operations that make it). The
    /// clearances of obstacles past the scenario's are left as they were.
    pub fn value_of_drawn(&self, x: &Vars, out: &mut Value) {
        out.x = *x;
        let (objective, min_clearance) = self.objective_of(
            &out.geo,
            false,
            &mut out.clearance,
            &mut out.nearest_segment,
        );
        out.objective = objective;
        out.min_clearance = min_clearance;
    }

    /// The objective and smallest clearance of the path `geo`, every clearance recorded.
    fn objective_of(
        &self,
        geo: &PathGeometry,
        stop_when_blocked: bool,
        clearance: &mut [f32; MAX_OBSTACLES],
        nearest_segment: &mut [u8; MAX_OBSTACLES],
    ) -> (f32, f32) {
        let (risk, min_clearance) = self.scan(geo, stop_when_blocked, |o, d, seg| {
            clearance[o] = d;
            nearest_segment[o] = seg;
        });
        let w = &self.scenario.weights;
        let risk_term = if w.risk == 0.0 { 0.0 } else { w.risk * risk };
        let objective =
            w.length * geo.total_length() + risk_term + w.control * self.form.len() as f32;
        (objective, min_clearance)
    }

    /// Clearance of every obstacle (`record(obstacle, clearance, nearest segment)`); returns D
    /// (infinite once an obstacle is within the clearance floor) and the smallest clearance.
    fn scan(
        &self,
        geo: &PathGeometry,
        stop_when_blocked: bool,
        mut record: impl FnMut(usize, f32, u8),
    ) -> (f32, f32) {
        let mut min_clearance = f32::INFINITY;
        let mut inv_sum = 0.0f32;
        let mut blocked = false;
        for (o, ob) in self.scenario.obstacles.iter().enumerate() {
            let c = v3(ob.center);
            let mut best = f32::INFINITY;
            let mut nearest = 0u8;
            for seg in 0..self.form.len() {
                let cl = self.closest_on(geo, seg, &c);
                if cl.distance < best {
                    best = cl.distance;
                    nearest = seg as u8;
                }
            }
            let d = best - ob.radius;
            record(o, d, nearest);
            if d < min_clearance {
                min_clearance = d;
            }
            if d > self.min_clearance {
                inv_sum += 1.0 / d;
            } else {
                blocked = true;
                if stop_when_blocked {
                    break;
                }
            }
        }
        let risk = if blocked {
            f32::INFINITY
        } else {
            inv_sum * self.risk_scale()
        };
        (risk, min_clearance)
    }

    /// The point of segment `seg` of the path `geo` nearest to the point `c`.
    fn closest_on(&self, geo: &PathGeometry, seg: usize, c: &V3) -> Closest {
        closest_drawn(
            &geo.starts[seg],
            &geo.ends[seg].p,
            self.form.kind(seg),
            geo.lengths[seg],
            self.radius,
            c,
        )
    }

    /// The factor that turns the sum of 1/d over obstacles into D (1/count for the mean).
    pub fn risk_scale(&self) -> f32 {
        let count = self.scenario.obstacles.len();
        match self.scenario.options.risk {
            RiskMeasure::Mean if count > 0 => 1.0 / count as f32,
            _ => 1.0,
        }
    }

    /// Exact first derivatives at the point `v` (from [`Problem::value`]).
    pub fn derivatives(&self, v: &Value) -> Derivatives {
        let mut out = Derivatives {
            residual: [0.0; 3],
            jac: [[0.0; MAX_VARS]; 3],
            grad: [0.0; MAX_VARS],
            clearance_grad: [[0.0; MAX_VARS]; MAX_OBSTACLES],
        };
        self.derivatives_into(v, &mut out);
        out
    }

    /// [`Problem::derivatives`] written into `out` (an SQP iteration reuses one buffer: on the
    /// device, moving these kilobytes costs more than computing them). Rows of `clearance_grad`
    /// beyond the scenario's obstacles are left as they were.
    pub fn derivatives_into(&self, v: &Value, out: &mut Derivatives) {
        let geo = &v.geo;
        let screws = self.screws(&v.x, geo);
        (out.residual, out.jac) = self.end_rows(geo, &screws);
        let w = &self.scenario.weights;
        let clearance_grad = &mut out.clearance_grad;
        let grad = &mut out.grad;
        *grad = [0.0; MAX_VARS];
        let risk_scale = w.risk * self.risk_scale();
        for (o, ob) in self.scenario.obstacles.iter().enumerate() {
            let c = v3(ob.center);
            let seg = usize::from(v.nearest_segment[o]);
            let cl = self.closest_on(geo, seg, &c);
            clearance_grad[o] = [0.0; MAX_VARS];
            if cl.distance > 0.0 {
                let normal = (cl.point - c) / cl.distance;
                let at_end = cl.where_ == Nearest::End;
                for k in 0..self.n {
                    if self.moves(k, seg, at_end) {
                        clearance_grad[o][k] = normal.dot(&screws[k].velocity(&cl.point));
                    }
                }
            }
            let d = v.clearance[o];
            if d > 0.0 && risk_scale != 0.0 {
                let s = -risk_scale / (d * d);
                for k in 0..self.n {
                    grad[k] += s * clearance_grad[o][k];
                }
            }
        }
        for i in 0..self.form.len() {
            grad[self.length_var(i)] += w.length * self.radius;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::form::Form;
    use crate::model::scenario::{Obstacle, Scenario, Workspace};

    fn space_scenario() -> Scenario {
        let mut s = Scenario::paper();
        s.options.workspace = Workspace::Space;
        s.target.position = [12.0, 8.0, 85.0];
        s.obstacles.clear();
        for (c, r) in [
            ([6.0, 4.0, 42.0], 9.0),
            ([-10.0, 14.0, 58.0], 8.0),
            ([22.0, -6.0, 62.0], 7.0),
        ] {
            s.obstacles
                .push(Obstacle {
                    center: c,
                    radius: r,
                })
                .unwrap();
        }
        s
    }

    /// Central differences in f32 agree with the analytic derivatives to a few parts in 10^3.
    fn check_gradients(p: &Problem, x: &Vars) -> usize {
        let mut objective_checks = 0;
        let v = p.value(x);
        let e = p.derivatives(&v);
        let h = 1e-3f32;
        for k in 0..p.n {
            let mut xp = *x;
            let mut xm = *x;
            xp[k] += h;
            xm[k] -= h;
            let (ep, em) = (p.value(&xp), p.value(&xm));
            let (rp, rm) = (p.end_constraint(&xp).0, p.end_constraint(&xm).0);
            for r in 0..p.m_eq {
                let fd = (rp[r] - rm[r]) / (2.0 * h);
                assert!(
                    (fd - e.jac[r][k]).abs() < 2e-2 * (1.0 + fd.abs()),
                    "jac[{r}][{k}] {fd} vs {}",
                    e.jac[r][k]
                );
            }
            for o in 0..p.scenario.obstacles.len() {
                let fd = (ep.clearance[o] - em.clearance[o]) / (2.0 * h);
                let an = e.clearance_grad[o][k];
                assert!(
                    (fd - an).abs() < 2e-2 * (1.0 + fd.abs()),
                    "clearance {o} var {k}: {fd} vs {an}"
                );
            }
            // The objective is only defined away from the obstacles.
            if [&v, &ep, &em]
                .iter()
                .all(|e| e.min_clearance > p.min_clearance)
            {
                let fd = (ep.objective - em.objective) / (2.0 * h);
                assert!(
                    (fd - e.grad[k]).abs() < 3e-2 * (1.0 + fd.abs()),
                    "objective var {k}: {fd} vs {}",
                    e.grad[k]
                );
                objective_checks += 1;
            }
        }
        objective_checks
    }

    #[test]
    fn analytic_derivatives_match_finite_differences_in_space() {
        let s = space_scenario();
        let mut objective_checks = 0;
        for word in ["RL", "LRL", "RRR", "RLR"] {
            let form = Form::parse(word).unwrap();
            let p = Problem::new(&s, form, 0);
            let mut x = [0.0; MAX_VARS];
            x[0] = 0.2;
            x[1] = -0.15;
            for i in 0..form.len() {
                x[p.length_var(i)] = 0.45 + 0.1 * i as f32;
                if let Some(k) = p.bevel_var(i) {
                    x[k] = 0.7 - 0.9 * i as f32;
                }
            }
            objective_checks += check_gradients(&p, &x);
        }
        assert!(objective_checks > 0);
    }

    #[test]
    fn analytic_derivatives_match_finite_differences_in_plane() {
        let s = Scenario::paper();
        let mut objective_checks = 0;
        let cases = [
            ("RL", 1, [-0.3, 0.5, 0.55, 0.0]),
            ("LRL", 0, [-0.3, 0.5, 0.55, 0.6]),
            ("RRR", 0b101, [-0.3, 0.5, 0.55, 0.6]),
            ("LRR", 0b10, [-0.3, 0.5, 0.55, 0.6]),
            // Near the paper's best RL: clear of every obstacle.
            ("RL", 1, [0.5, 0.64, 0.8, 0.0]),
            ("RL", 1, [-0.5, 0.64, 0.8, 0.0]),
        ];
        for (word, sides, v) in cases {
            let form = Form::parse(word).unwrap();
            let p = Problem::new(&s, form, sides);
            let mut x = [0.0; MAX_VARS];
            x[..4].copy_from_slice(&v);
            objective_checks += check_gradients(&p, &x);
        }
        assert!(objective_checks > 0);
    }
}
