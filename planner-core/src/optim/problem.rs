//! One form's optimisation problem: its variables, bounds, the path they draw and the end-point
//! constraint (the objective and the clearances are in [`super::objective`]).
//!
//! Variables (all of order one, so one trust region fits all): the insertion angles theta1 (and
//! theta2 in 3-D), each segment's length divided by the arc radius (for an arc, its turning angle),
//! and in 3-D the bevel rotation before each arc. In plane mode each arc's side is fixed by the
//! problem ([`Problem::plane`]), so bevel rotations are constants of 0 or pi.

use crate::model::broad::Broad;
use crate::model::form::{Form, SegmentKind, MAX_CONTROL_DEGREE};
use crate::model::kinematics::{
    entry_basis, insertion_frame, rotate, Frame, PathGeometry, Screw, V3,
};
use crate::model::scenario::{Scenario, Workspace};
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
    /// 1 - cos of the tilt bound, as 2 sin²(bound / 2): exact in f32 even for a bound of a
    /// fraction of a degree, where cos itself rounds to within 6e-8 of 1 (found by fuzzing: a
    /// 0.4-degree bound was exceeded by 2e-5 degrees).
    pub vers_max_tilt: f32,
    /// The entry frame (columns b1, b2, b3; b3 the nominal axis).
    pub basis: Matrix3<f32>,
    /// A fixed start: the entry on its axis when the tilt bound is zero, or a continuation's tip
    /// in tissue. No insertion angles then; in 3-D a bevel variable before every arc, the first
    /// one included (the rotation done where the path starts).
    pub start: Option<Frame>,
    /// End-point tolerance the optimiser solves to (mm): a hundredth of the scenario's, at most
    /// 1 um, but never finer than f32 resolves at these coordinates (worked out once: every
    /// restoration needs it).
    pub equality_tolerance: f32,
    /// The reach of the risk term (`planner.risk_within_mm`), if the scenario sets one.
    pub reach: Option<Reach>,
    /// The broad phase over the obstacles (with a reach only: without one every obstacle is
    /// measured for D anyway).
    pub broad: Option<Broad>,
    entry: V3,
    target: V3,
}

/// The reach r of the risk term: an obstacle adds 1/d − 1/r while d < r.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// r (mm).
    pub within: f32,
    /// 1/r.
    pub inverse: f32,
}

pub(super) fn v3(a: [f32; 3]) -> V3 {
    V3::new(a[0], a[1], a[2])
}

/// 1 - cos(a), as 2 sin²(a / 2).
fn versine(a: f32) -> f32 {
    let h = crate::fmath::sin(0.5 * a);
    2.0 * h * h
}

/// Relative shrink of the tilt and arc bounds (about 30 f32 ulps).
const BOUND_SHRINK: f32 = 1.0 - 4e-6;

impl<'a> Problem<'a> {
    /// The problem of `form`; in plane mode `sides` bit i set means arc i turns to the negative side.
    pub fn new(scenario: &'a Scenario, form: Form, sides: u8) -> Problem<'a> {
        let plane = scenario.options.workspace == Workspace::PlaneYz;
        let radius = scenario.planned_radius();
        // The optimiser's bounds sit a few f32 ulps inside the scenario's, so a path at a bound
        // still respects it when its reported numbers are rounded or re-evaluated in f64.
        let tilt = scenario.entry.max_tilt_deg.to_radians() * BOUND_SHRINK;
        let max_arc = scenario.needle.max_arc_deg.to_radians() * BOUND_SHRINK;
        let max_line = scenario.max_line_length() / radius * BOUND_SHRINK;
        let mut lower = [0.0; MAX_VARS];
        let mut upper = [0.0; MAX_VARS];
        let basis = entry_basis(scenario.entry.direction);
        let entry = v3(scenario.entry.position);
        // A tilt bound of zero (a template or a guide) fixes the posture: the path starts on the
        // axis, with no angle variables and no cone row (a cone of zero width is a degenerate
        // constraint the QP cannot hold).
        let start = (tilt == 0.0).then(|| insertion_frame(entry, &basis, 0.0, 0.0));
        let angles = match (start.is_some(), plane) {
            (true, _) => 0,
            (false, true) => 1,
            (false, false) => 2,
        };
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
            // Twice the check's margin above the scenario's minimum (see `check::check`).
            min_clearance: (scenario.options.min_clearance + 2.0 * scenario.resolution())
                .max(CLEARANCE_FLOOR),
            cos_max_tilt: crate::fmath::cos(tilt),
            vers_max_tilt: versine(tilt),
            basis,
            start,
            equality_tolerance: (scenario.target.tolerance * 0.01)
                .min(1e-3)
                .max(scenario.resolution()),
            reach: scenario.options.risk_within_mm.map(|r| Reach {
                within: r,
                inverse: 1.0 / r,
            }),
            broad: scenario
                .options
                .risk_within_mm
                .map(|_| Broad::new(&scenario.obstacles)),
            entry,
            target: v3(scenario.target.position),
        }
    }

    /// The problem of continuing along `form` from the tip frame `start` (always in 3-D): the
    /// variables are the segments' lengths and the bevel rotation before every arc.
    pub fn continuation(scenario: &'a Scenario, form: Form, start: Frame) -> Problem<'a> {
        // Changed in place: a copy of the problem from the entry would hold a second broad
        // phase (about 10 bytes a sphere) on the stack.
        let mut p = Problem::new(scenario, form, 0);
        let mut lengths = [0.0; MAX_CONTROL_DEGREE];
        for (i, l) in lengths.iter_mut().enumerate().take(form.len()) {
            *l = p.upper[p.length_var(i)];
        }
        p.plane = false;
        p.m_eq = 3;
        p.fixed_bevels = [0.0; MAX_CONTROL_DEGREE];
        p.start = Some(start);
        p.basis = start.r;
        p.lower = [0.0; MAX_VARS];
        p.upper = [0.0; MAX_VARS];
        for (u, l) in p.upper.iter_mut().zip(&lengths).take(form.len()) {
            *u = *l;
        }
        p.n = form.len();
        for _ in 0..form.arc_count() {
            // Bevel angles are periodic; the box only keeps them finite.
            p.lower[p.n] = -4.0 * core::f32::consts::PI;
            p.upper[p.n] = 4.0 * core::f32::consts::PI;
            p.n += 1;
        }
        p
    }

    /// Number of insertion-angle variables: 2 in 3-D, 1 in the plane, 0 for a fixed posture or
    /// a continuation.
    pub fn angle_count(&self) -> usize {
        match (self.start.is_some(), self.plane) {
            (true, _) => 0,
            (false, true) => 1,
            (false, false) => 2,
        }
    }

    /// Whether the tilt cone constrains this problem (3-D plans from the entry).
    pub fn has_tilt(&self) -> bool {
        !self.plane && self.start.is_none()
    }

    /// Index of segment `i`'s length variable.
    pub fn length_var(&self, i: usize) -> usize {
        i + self.angle_count()
    }

    /// Index of the bevel variable before segment `i`, if it has one.
    pub fn bevel_var(&self, i: usize) -> Option<usize> {
        if self.plane || self.form.kind(i) != SegmentKind::Arc {
            return None;
        }
        let arcs_before = (0..i)
            .filter(|&j| self.form.kind(j) == SegmentKind::Arc)
            .count();
        Some(self.angle_count() + self.form.len() + arcs_before)
    }

    /// Whether the insertion heading is fixed: a tilt bound of zero, or a continuation.
    pub fn heading_fixed(&self) -> bool {
        self.start.is_some()
    }

    /// Writes the insertion angles `theta1`, `theta2` into `x`, as far as `x` has them.
    pub fn set_angles(&self, x: &mut Vars, theta1: f32, theta2: f32) {
        let count = self.angle_count();
        for (k, v) in x.iter_mut().zip([theta1, theta2]).take(count) {
            *k = v;
        }
    }

    /// theta1, theta2 of `x`.
    pub fn angles(&self, x: &Vars) -> (f32, f32) {
        match self.angle_count() {
            0 => (0.0, 0.0),
            1 => (x[0], 0.0),
            _ => (x[0], x[1]),
        }
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

    /// cos(tilt) - cos(max tilt): non-negative inside the tilt cone. Computed as
    /// vers(max) - (vers(t1) + cos(t1) vers(t2)), the same quantity without the cancellation.
    pub fn tilt_margin(&self, x: &Vars) -> f32 {
        if self.start.is_some() {
            return 1.0;
        }
        let (t1, t2) = self.angles(x);
        self.vers_max_tilt - (versine(t1) + crate::fmath::cos(t1) * versine(t2))
    }

    /// Gradient of [`Problem::tilt_margin`].
    pub fn tilt_margin_grad(&self, x: &Vars) -> Vars {
        let mut g = [0.0; MAX_VARS];
        if self.start.is_some() {
            return g;
        }
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
        let first = match self.start {
            Some(frame) => frame,
            None => insertion_frame(self.entry, &self.basis, t1, t2),
        };
        PathGeometry::build(
            self.form,
            first,
            &self.lengths(x),
            &self.bevels(x),
            self.radius,
        )
    }

    /// [`Problem::geometry`] written into `geo`, a path of this problem.
    pub fn geometry_into(&self, x: &Vars, geo: &mut PathGeometry) {
        let (t1, t2) = self.angles(x);
        let first = insertion_frame(self.entry, &self.basis, t1, t2);
        geo.rebuild(first, &self.lengths(x), &self.bevels(x));
    }

    /// The screw of every variable, for points downstream of all of them.
    pub(super) fn screws(&self, x: &Vars, geo: &PathGeometry) -> [Screw; MAX_VARS] {
        let mut s = [Screw::ZERO; MAX_VARS];
        let b1: V3 = self.basis.column(0).into();
        let b2: V3 = self.basis.column(1).into();
        if self.start.is_none() {
            s[0] = Screw::about(b1, self.entry, V3::zeros());
            if !self.plane {
                s[1] = Screw::about(rotate(b2, b1, x[0]), self.entry, V3::zeros());
            }
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
    pub(super) fn moves(&self, k: usize, seg: usize, at_end: bool) -> bool {
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

    /// The end-point residual of the path `geo` (the rows of [`Problem::end_rows`] without their
    /// Jacobian: a restoration that has reached the target needs no more).
    pub fn end_residual(&self, geo: &PathGeometry) -> [f32; 3] {
        let diff = geo.end() - self.target;
        let mut residual = [0.0; 3];
        let rows = self.constraint_rows();
        for (r, axis) in rows.iter().enumerate().take(self.m_eq) {
            residual[r] = diff.dot(axis);
        }
        residual
    }

    /// End-point residual and its Jacobian only.
    #[cfg(test)]
    pub fn end_constraint(&self, x: &Vars) -> ([f32; 3], [Vars; 3]) {
        let geo = self.geometry(x);
        self.end_rows(&geo, &self.screws(x, &geo))
    }

    /// End-point residual and Jacobian of the path `geo` with variable screws `screws`.
    pub(super) fn end_rows(
        &self,
        geo: &PathGeometry,
        screws: &[Screw; MAX_VARS],
    ) -> ([f32; 3], [Vars; 3]) {
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
}
