//! The objective F = a1 L + a2 D + a4 N and the clearances of one form's problem at a point, and
//! their exact first derivatives (every parameter moves the downstream path as a rigid screw).
//!
//! D is exact over every obstacle (within `planner.risk_within_mm` when the scenario sets it).
//! What the optimiser keeps per obstacle at a point, clearance and gradient rows, is kept for the
//! *near set* only: the [`MAX_NEAR`] obstacles with the smallest clearance (of those within the
//! reach), held in index order. A scenario of at most [`MAX_NEAR`] obstacles without a reach has
//! them all, slot i holding obstacle i, so its plans are those of a planner without slots. With
//! more, the QP's clearance rows, the model Hessian, the escape from a near miss and the KKT
//! residual see the near set (the obstacles a step can reach first); D and its gradient still
//! sum every obstacle.

use super::problem::{v3, Problem, Vars, MAX_VARS};
use crate::model::broad::Set;
use crate::model::clearance::{closest_drawn, Closest, Nearest};
use crate::model::kinematics::{PathGeometry, V3};
use crate::model::scenario::RiskMeasure;

/// Obstacles the optimiser weighs in rows and gradients at one point (the near set).
pub const MAX_NEAR: usize = 32;

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
    /// Slots of the near set in use.
    pub near_count: usize,
    /// The obstacle in each slot, increasing.
    pub near: [u16; MAX_NEAR],
    /// Clearance d of each slot's obstacle (mm).
    pub clearance: [f32; MAX_NEAR],
    /// The segment nearest to each slot's obstacle.
    pub nearest_segment: [u8; MAX_NEAR],
    /// Smallest clearance (of the obstacles within the reach: infinite when none is).
    pub min_clearance: f32,
    /// The obstacles whose clearance was measured (every one without a reach; with one, those
    /// the broad phase found): the derivatives go over the same.
    pub measured: Set,
}

impl Value {
    /// Every clearance above the floor and the tilt within its bound.
    pub fn admissible(&self, p: &Problem) -> bool {
        self.min_clearance > p.min_clearance
            && self.objective.is_finite()
            && p.tilt_margin(&self.x) >= 0.0
    }

    /// The slot of obstacle `o`, if it is in the near set.
    pub fn slot_of(&self, o: usize) -> Option<usize> {
        let near = self.near.get(..self.near_count)?;
        near.binary_search(&(o as u16)).ok()
    }
}

/// The slots of a near set: count, obstacle, clearance and nearest segment of each.
type Slots<'a> = (
    &'a mut usize,
    &'a mut [u16; MAX_NEAR],
    &'a mut [f32; MAX_NEAR],
    &'a mut [u8; MAX_NEAR],
);

/// Offers obstacle `o` at clearance `d` (nearest segment `seg`) to the near set `slots`;
/// obstacles come in increasing index order. A full set gives up its farthest (the last of
/// equals) for a nearer one.
fn offer(slots: Slots, o: usize, d: f32, seg: u8) {
    let (count, near, clearance, nearest_segment) = slots;
    let mut at = *count;
    if at >= MAX_NEAR {
        let mut worst = 0;
        for s in 1..MAX_NEAR {
            if clearance[s] >= clearance[worst] {
                worst = s;
            }
        }
        if !(d < clearance[worst]) {
            return;
        }
        for s in worst..MAX_NEAR - 1 {
            near[s] = near[s + 1];
            clearance[s] = clearance[s + 1];
            nearest_segment[s] = nearest_segment[s + 1];
        }
        at = MAX_NEAR - 1;
    } else {
        *count += 1;
    }
    near[at] = o as u16;
    clearance[at] = d;
    nearest_segment[at] = seg;
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
    /// Gradient of the clearance of each slot of the point's near set.
    pub clearance_grad: [Vars; MAX_NEAR],
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
        let mut v = Value {
            x: *x,
            geo: self.geometry(x),
            objective: 0.0,
            near_count: 0,
            near: [0; MAX_NEAR],
            clearance: [f32::INFINITY; MAX_NEAR],
            nearest_segment: [0; MAX_NEAR],
            min_clearance: f32::INFINITY,
            measured: Set::default(),
        };
        self.objective_of(&mut v, stop_when_blocked);
        v
    }

    /// [`Problem::value`] written into `out` when `out.geo` already holds the path of `x` (a
    /// line search reuses one buffer, and the restoration has just drawn the path: on the
    /// device, moving a `Value` costs more than many of the operations that make it). The slots
    /// past the near set's are left as they were.
    pub fn value_of_drawn(&self, x: &Vars, out: &mut Value) {
        out.x = *x;
        out.near_count = 0;
        self.objective_of(out, false);
    }

    /// The objective, the smallest clearance and the near set of the path `v.geo`.
    fn objective_of(&self, v: &mut Value, stop_when_blocked: bool) {
        v.measured = self.candidates(&v.geo);
        let (risk, min_clearance) =
            self.scan(&v.geo, &v.measured, stop_when_blocked, |o, d, seg| {
                let slots = (
                    &mut v.near_count,
                    &mut v.near,
                    &mut v.clearance,
                    &mut v.nearest_segment,
                );
                offer(slots, o, d, seg);
            });
        let w = &self.scenario.weights;
        let risk_term = if w.risk == 0.0 { 0.0 } else { w.risk * risk };
        v.objective =
            w.length * v.geo.total_length() + risk_term + w.control * self.form.len() as f32;
        v.min_clearance = min_clearance;
    }

    /// The obstacles whose clearance a scan of `geo` measures: those the broad phase finds within
    /// the reach, or every one without a reach.
    pub(crate) fn candidates(&self, geo: &PathGeometry) -> Set {
        match (&self.reach, &self.broad) {
            (Some(r), Some(b)) => b.near_path(&self.scenario.obstacles, geo, r.within),
            _ => Set::all(self.scenario.obstacles.len()),
        }
    }

    /// Clearance and nearest segment of obstacle `o` from the path `geo`.
    fn clearance_of(&self, geo: &PathGeometry, o: usize) -> Option<(f32, u8)> {
        let ob = self.scenario.obstacles.get(o)?;
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
        Some((best - ob.radius, nearest))
    }

    /// Clearance of every obstacle of `candidates` within the reach (`record(obstacle,
    /// clearance, nearest segment)`, in index order); returns D (infinite once an obstacle is within the clearance
    /// floor) and the smallest clearance.
    fn scan(
        &self,
        geo: &PathGeometry,
        candidates: &Set,
        stop_when_blocked: bool,
        mut record: impl FnMut(usize, f32, u8),
    ) -> (f32, f32) {
        let mut min_clearance = f32::INFINITY;
        let mut inv_sum = 0.0f32;
        let mut blocked = false;
        for o in candidates.iter() {
            let Some((d, nearest)) = self.clearance_of(geo, o) else {
                continue;
            };
            if let Some(r) = &self.reach {
                if !(d < r.within) {
                    continue;
                }
            }
            record(o, d, nearest);
            if d < min_clearance {
                min_clearance = d;
            }
            if d > self.min_clearance {
                inv_sum += match &self.reach {
                    Some(r) => 1.0 / d - r.inverse,
                    None => 1.0 / d,
                };
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
            clearance_grad: [[0.0; MAX_VARS]; MAX_NEAR],
        };
        self.derivatives_into(v, &mut out);
        out
    }

    /// [`Problem::derivatives`] written into `out` (an SQP iteration reuses one buffer: on the
    /// device, moving these kilobytes costs more than computing them). Rows of `clearance_grad`
    /// past the near set's are left as they were. D's gradient sums every obstacle within the
    /// reach in index order; one outside the near set has its row worked out on the way.
    pub fn derivatives_into(&self, v: &Value, out: &mut Derivatives) {
        let geo = &v.geo;
        let screws = self.screws(&v.x, geo);
        (out.residual, out.jac) = self.end_rows(geo, &screws);
        let w = &self.scenario.weights;
        let clearance_grad = &mut out.clearance_grad;
        let grad = &mut out.grad;
        *grad = [0.0; MAX_VARS];
        let risk_scale = w.risk * self.risk_scale();
        let mut slot = 0;
        let mut spare = [0.0f32; MAX_VARS];
        for o in v.measured.iter() {
            let in_slot = slot < v.near_count && usize::from(v.near[slot]) == o;
            let (d, seg, row) = if in_slot {
                slot += 1;
                let s = slot - 1;
                let seg = usize::from(v.nearest_segment[s]);
                (v.clearance[s], seg, &mut clearance_grad[s])
            } else {
                // Past the near set: only D's gradient needs it.
                let Some((d, seg)) = self.clearance_of(geo, o) else {
                    continue;
                };
                if self.reach.as_ref().is_some_and(|r| !(d < r.within)) || risk_scale == 0.0 {
                    continue;
                }
                (d, usize::from(seg), &mut spare)
            };
            let Some(ob) = self.scenario.obstacles.get(o) else {
                continue;
            };
            let c = v3(ob.center);
            let cl = self.closest_on(geo, seg, &c);
            *row = [0.0; MAX_VARS];
            if cl.distance > 0.0 {
                let normal = (cl.point - c) / cl.distance;
                let at_end = cl.where_ == Nearest::End;
                for k in 0..self.n {
                    if self.moves(k, seg, at_end) {
                        row[k] = normal.dot(&screws[k].velocity(&cl.point));
                    }
                }
            }
            if d > 0.0 && risk_scale != 0.0 {
                let s = -risk_scale / (d * d);
                for k in 0..self.n {
                    grad[k] += s * row[k];
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
