//! One form's optimisation problem: its variables, bounds, and the evaluation of the objective,
//! the end-point constraint and the clearances with exact first derivatives.
//!
//! Variables (all of order one, so one trust region fits all): the insertion angles theta1 (and
//! theta2 in 3-D), each segment's length divided by the arc radius (for an arc, its turning angle),
//! and in 3-D the bevel rotation before each arc. In plane mode each arc's side is fixed by the
//! problem ([`Problem::plane`]), so bevel rotations are constants of 0 or pi.

use crate::clearance::{closest, Nearest};
use crate::form::{Form, SegmentKind, MAX_CONTROL_DEGREE};
use crate::kinematics::{entry_basis, insertion_frame, rotate, PathGeometry, Screw, V3};
use crate::scenario::{RiskMeasure, Scenario, Workspace, MAX_OBSTACLES};
use crate::verify::max_line_length;
use nalgebra::Matrix3;

/// Most optimisation variables of any form: two angles, four lengths, four bevels.
pub const MAX_VARS: usize = 2 + 2 * MAX_CONTROL_DEGREE;

/// A vector of optimisation variables (only the first [`Problem::n`] are used).
pub type Vars = [f32; MAX_VARS];

/// Clearance floor used when the scenario asks for none: keeps reported clearances positive.
const CLEARANCE_FLOOR: f32 = 1e-3;

/// The problem of one form (and, in plane mode, one side assignment of its arcs).
#[derive(Clone, Debug)]
pub struct Problem<'a> {
    /// The scenario.
    pub scenario: &'a Scenario,
    /// The form.
    pub form: Form,
    /// Plane mode: bevel rotations are fixed, theta2 is absent.
    pub plane: bool,
    /// Plane mode: the fixed bevel rotation before each segment (0 or pi).
    pub fixed_bevels: [f32; MAX_CONTROL_DEGREE],
    /// Number of variables.
    pub n: usize,
    /// Lower bounds.
    pub lower: Vars,
    /// Upper bounds.
    pub upper: Vars,
    /// Rows of the end-point constraint: 2 in plane mode, 3 in space.
    pub m_eq: usize,
    /// Arc radius (mm).
    pub radius: f32,
    /// Smallest clearance allowed (mm).
    pub min_clearance: f32,
    /// cos of the tilt bound.
    pub cos_max_tilt: f32,
    /// The entry frame (columns b1, b2, b3; b3 the nominal axis).
    pub basis: Matrix3<f32>,
    entry: V3,
    target: V3,
}

/// The objective and the clearances at one point (no derivatives: what seeds and line searches
/// need).
#[derive(Clone, Debug)]
pub struct Value {
    /// The variables.
    pub x: Vars,
    /// The path.
    pub geo: PathGeometry,
    /// L (mm).
    pub length: f32,
    /// D (infinite when a clearance is not positive).
    pub risk: f32,
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

fn v3(a: [f32; 3]) -> V3 {
    V3::new(a[0], a[1], a[2])
}

/// Relative shrink of the tilt and arc bounds (about 30 f32 ulps).
const BOUND_SHRINK: f32 = 1.0 - 4e-6;

impl<'a> Problem<'a> {
    /// The problem of `form`; in plane mode `sides` bit i set means arc i turns to the negative side.
    pub fn new(scenario: &'a Scenario, form: Form, sides: u8) -> Problem<'a> {
        let plane = scenario.options.workspace == Workspace::PlaneYz;
        let radius = scenario.needle.curvature_radius;
        // The optimiser's bounds sit a few f32 ulps inside the scenario's, so a path at a bound
        // still respects it when its reported numbers are rounded or re-evaluated in f64.
        let tilt = scenario.entry.max_tilt_deg.to_radians() * BOUND_SHRINK;
        let max_arc = scenario.needle.max_arc_deg.to_radians() * BOUND_SHRINK;
        let max_line = max_line_length(scenario) / radius * BOUND_SHRINK;
        let mut lower = [0.0; MAX_VARS];
        let mut upper = [0.0; MAX_VARS];
        let angles = if plane { 1 } else { 2 };
        for k in 0..angles {
            lower[k] = -tilt;
            upper[k] = tilt;
        }
        let mut n = angles;
        for i in 0..form.len() {
            upper[n] = match form.kind(i) {
                SegmentKind::Arc => max_arc,
                SegmentKind::Line => max_line,
            };
            n += 1;
        }
        if !plane {
            for _ in 0..form.arc_count() {
                // Bevel angles are periodic; the box only keeps them finite.
                lower[n] = -4.0 * core::f32::consts::PI;
                upper[n] = 4.0 * core::f32::consts::PI;
                n += 1;
            }
        }
        let mut fixed_bevels = [0.0; MAX_CONTROL_DEGREE];
        if plane {
            // Roll by pi whenever the next arc turns to the other side than the bevel faces now.
            let mut facing_negative = false;
            let mut arc = 0;
            for (i, b) in fixed_bevels.iter_mut().enumerate().take(form.len()) {
                if form.kind(i) == SegmentKind::Arc {
                    let negative = sides & (1 << arc) != 0;
                    if negative != facing_negative {
                        *b = core::f32::consts::PI;
                        facing_negative = negative;
                    }
                    arc += 1;
                }
            }
        }
        Problem {
            scenario,
            form,
            plane,
            fixed_bevels,
            n,
            lower,
            upper,
            m_eq: if plane { 2 } else { 3 },
            radius,
            min_clearance: scenario.options.min_clearance.max(CLEARANCE_FLOOR),
            cos_max_tilt: crate::fmath::cos(tilt),
            basis: entry_basis(scenario.entry.direction),
            entry: v3(scenario.entry.position),
            target: v3(scenario.target.position),
        }
    }

    /// Index of segment `i`'s length variable.
    pub fn length_var(&self, i: usize) -> usize {
        i + if self.plane { 1 } else { 2 }
    }

    /// Index of the bevel variable before segment `i`, if it has one.
    pub fn bevel_var(&self, i: usize) -> Option<usize> {
        if self.plane || self.form.kind(i) != SegmentKind::Arc {
            return None;
        }
        let arcs_before = (0..i)
            .filter(|&j| self.form.kind(j) == SegmentKind::Arc)
            .count();
        Some(2 + self.form.len() + arcs_before)
    }

    /// theta1, theta2 of `x`.
    pub fn angles(&self, x: &Vars) -> (f32, f32) {
        (x[0], if self.plane { 0.0 } else { x[1] })
    }

    /// Bevel rotation before each segment.
    pub fn bevels(&self, x: &Vars) -> [f32; MAX_CONTROL_DEGREE] {
        let mut b = self.fixed_bevels;
        for (i, bi) in b.iter_mut().enumerate().take(self.form.len()) {
            if let Some(k) = self.bevel_var(i) {
                *bi = x[k];
            }
        }
        b
    }

    /// Segment lengths (mm).
    pub fn lengths(&self, x: &Vars) -> [f32; MAX_CONTROL_DEGREE] {
        let mut l = [0.0; MAX_CONTROL_DEGREE];
        for (i, li) in l.iter_mut().enumerate().take(self.form.len()) {
            *li = x[self.length_var(i)] * self.radius;
        }
        l
    }

    /// cos(tilt) - cos(max tilt): non-negative inside the tilt cone.
    pub fn tilt_margin(&self, x: &Vars) -> f32 {
        let (t1, t2) = self.angles(x);
        crate::fmath::cos(t1) * crate::fmath::cos(t2) - self.cos_max_tilt
    }

    /// Gradient of [`Problem::tilt_margin`].
    pub fn tilt_margin_grad(&self, x: &Vars) -> Vars {
        let mut g = [0.0; MAX_VARS];
        let (t1, t2) = self.angles(x);
        g[0] = -crate::fmath::sin(t1) * crate::fmath::cos(t2);
        if !self.plane {
            g[1] = -crate::fmath::cos(t1) * crate::fmath::sin(t2);
        }
        g
    }

    /// The path of `x`.
    pub fn geometry(&self, x: &Vars) -> PathGeometry {
        let (t1, t2) = self.angles(x);
        let first = insertion_frame(self.entry, &self.basis, t1, t2);
        PathGeometry::build(
            self.form,
            first,
            &self.lengths(x),
            &self.bevels(x),
            self.radius,
        )
    }

    /// The screw of every variable, for points downstream of all of them.
    fn screws(&self, x: &Vars, geo: &PathGeometry) -> [Screw; MAX_VARS] {
        let mut s = [Screw::ZERO; MAX_VARS];
        let b1: V3 = self.basis.column(0).into();
        let b2: V3 = self.basis.column(1).into();
        s[0] = Screw::about(b1, self.entry, V3::zeros());
        if !self.plane {
            s[1] = Screw::about(rotate(b2, b1, x[0]), self.entry, V3::zeros());
        }
        for i in 0..self.form.len() {
            let ls = geo.length_screw(i);
            s[self.length_var(i)] = Screw {
                w: ls.w * self.radius,
                v: ls.v * self.radius,
            };
            if let Some(k) = self.bevel_var(i) {
                s[k] = geo.bevel_screw(i);
            }
        }
        s
    }

    /// Whether variable `k` moves the point at arc length `at` of segment `seg` (`at_end`: it is
    /// the segment's end).
    fn moves(&self, k: usize, seg: usize, at_end: bool) -> bool {
        let first_len = self.length_var(0);
        if k < first_len {
            return true;
        }
        if k < first_len + self.form.len() {
            let j = k - first_len;
            return j < seg || (j == seg && at_end);
        }
        // A bevel variable: it rolls its own segment and everything after.
        (0..=seg).any(|i| self.bevel_var(i) == Some(k))
    }

    /// End-point residual and its Jacobian only (for restoration).
    pub fn end_constraint(&self, x: &Vars) -> ([f32; 3], [Vars; 3]) {
        let geo = self.geometry(x);
        self.end_rows(&geo, &self.screws(x, &geo))
    }

    /// End-point residual and Jacobian of the path `geo` with variable screws `screws`.
    fn end_rows(&self, geo: &PathGeometry, screws: &[Screw; MAX_VARS]) -> ([f32; 3], [Vars; 3]) {
        let end = geo.end();
        let diff = end - self.target;
        let mut residual = [0.0; 3];
        let mut jac = [[0.0; MAX_VARS]; 3];
        let rows = self.constraint_rows();
        for (r, axis) in rows.iter().enumerate().take(self.m_eq) {
            residual[r] = diff.dot(axis);
            for k in 0..self.n {
                jac[r][k] = screws[k].velocity(&end).dot(axis);
            }
        }
        (residual, jac)
    }

    /// Directions of the end-point constraint rows (plane mode drops the plane normal).
    fn constraint_rows(&self) -> [V3; 3] {
        let b1: V3 = self.basis.column(0).into();
        let b2: V3 = self.basis.column(1).into();
        let b3: V3 = self.basis.column(2).into();
        if self.plane {
            [b2, b3, b1]
        } else {
            [b1, b2, b3]
        }
    }

    /// Objective and clearances at `x`.
    pub fn value(&self, x: &Vars) -> Value {
        self.value_or_blocked(x, false)
    }

    /// Like [`Problem::value`], but with `stop_when_blocked` the scan of the obstacles stops at the
    /// first one the path touches (the value is then inadmissible and only `min_clearance` is
    /// meaningful): a sweep over many seeds needs no more.
    pub fn value_or_blocked(&self, x: &Vars, stop_when_blocked: bool) -> Value {
        let geo = self.geometry(x);
        let mut clearance = [f32::INFINITY; MAX_OBSTACLES];
        let mut nearest_segment = [0u8; MAX_OBSTACLES];
        let (risk, min_clearance) = self.scan(&geo, stop_when_blocked, |o, d, seg| {
            clearance[o] = d;
            nearest_segment[o] = seg;
        });
        let w = &self.scenario.weights;
        let length = geo.total_length();
        let risk_term = if w.risk == 0.0 { 0.0 } else { w.risk * risk };
        let objective = w.length * length + risk_term + w.control * self.form.len() as f32;
        Value {
            x: *x,
            geo,
            length,
            risk,
            objective,
            clearance,
            nearest_segment,
            min_clearance,
        }
    }

    /// Objective and smallest clearance only (what a sweep over many seeds needs), stopping at
    /// the first obstacle the path touches.
    pub fn score(&self, x: &Vars) -> (f32, f32) {
        let geo = self.geometry(x);
        let (risk, min_clearance) = self.scan(&geo, true, |_, _, _| {});
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
                let cl = closest(
                    &geo.starts[seg],
                    self.form.kind(seg),
                    geo.lengths[seg],
                    self.radius,
                    &c,
                );
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
            let cl = closest(
                &geo.starts[seg],
                self.form.kind(seg),
                geo.lengths[seg],
                self.radius,
                &c,
            );
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
    use crate::scenario::{Obstacle, Workspace};

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
            if [v.risk, ep.risk, em.risk].iter().all(|r| r.is_finite()) {
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
