//! "Path classification": the best path of one form.
//!
//! For every side assignment of the arcs (plane mode) or every seed plane (3-D), seeds are moved
//! onto the target and scored; the best distinct ones are refined by the SQP; the best refined
//! path is re-checked by [`crate::check`] and reported with the numbers the check measured.

use crate::check::check;
use crate::model::form::{Form, SegmentKind, MAX_CONTROL_DEGREE};
use crate::model::kinematics::{entry_basis, insertion_frame, V3};
use crate::model::scenario::{Scenario, Workspace};
use crate::optim::problem::{Problem, Vars};
use crate::optim::sqp::{self, LocalSolution};
use crate::report::{FormOutcome, Insertion, SegmentPlan, Segments, SolveStatus};
use crate::search::escape::escape;
use crate::search::seeds::{sweep, SeedSink};

/// Seed planes tried in 3-D (turns of the plane about the entry-target line over half a turn).
pub const SPACE_PLANES: usize = 8;
/// Distinct seeds refined per side assignment (plane) or per seed plane (3-D).
pub const REFINED_PER_GROUP: usize = 4;
/// Near misses moved out of their obstacles per group, when the group has room for more seeds.
pub const NEAR_MISSES_PER_GROUP: usize = 2;

/// The best few admissible seeds, kept distinct.
struct Shortlist {
    items: heapless::Vec<(f32, Vars), REFINED_PER_GROUP>,
    /// The near misses that cut least into obstacles (their smallest clearance, variables).
    near: heapless::Vec<(f32, Vars), NEAR_MISSES_PER_GROUP>,
    /// Variables compared when telling seeds apart.
    n: usize,
}

impl Shortlist {
    fn new(n: usize) -> Self {
        Shortlist {
            items: heapless::Vec::new(),
            near: heapless::Vec::new(),
            n,
        }
    }
}

impl SeedSink for Shortlist {
    fn bound(&self) -> f32 {
        if !self.items.is_full() {
            return f32::INFINITY;
        }
        self.items
            .iter()
            .map(|(f, _)| *f)
            .fold(f32::NEG_INFINITY, f32::max)
    }

    fn offer(&mut self, objective: f32, at: &Vars) {
        keep_best(&mut self.items, objective, at, self.n);
    }

    fn near_miss(&mut self, min_clearance: f32, x: &dyn Fn() -> Option<Vars>) {
        let worst = self
            .near
            .iter()
            .map(|(c, _)| -*c)
            .fold(f32::NEG_INFINITY, f32::max);
        if self.near.is_full() && -min_clearance >= worst {
            return;
        }
        if let Some(x) = x() {
            keep_best(&mut self.near, -min_clearance, &x, self.n);
        }
    }
}

/// Keeps in `items` the distinct points of lowest `key`: a point near one already kept replaces it
/// if lower, otherwise it takes the place of the highest when that is higher.
fn keep_best<const N: usize>(
    items: &mut heapless::Vec<(f32, Vars), N>,
    key: f32,
    at: &Vars,
    n: usize,
) {
    let near = |x: &Vars| (0..n).all(|k| libm::fabsf(x[k] - at[k]) < 0.2);
    if let Some(i) = items.iter().position(|(_, x)| near(x)) {
        if key < items[i].0 {
            items[i] = (key, *at);
        }
        return;
    }
    if items.is_full() {
        let worst = (0..items.len())
            .max_by(|&a, &b| items[a].0.total_cmp(&items[b].0))
            .unwrap_or(0);
        if key >= items[worst].0 {
            return;
        }
        items.swap_remove(worst);
    }
    // Room was made above.
    let _ = items.push((key, *at));
}

/// Effort spent on a form.
#[derive(Default)]
struct Effort {
    iterations: u32,
    evaluations: u32,
}

/// Scores every seed of one group and refines the shortlist and the `extra` starts; returns the
/// best local solution.
fn solve_group(
    p: &Problem,
    psi: f32,
    sides: u8,
    extra: &[Vars],
    known: &mut Basins,
    effort: &mut Effort,
) -> Option<LocalSolution> {
    let mut list = Shortlist::new(p.n);
    let arc_sides = if p.plane {
        1
    } else {
        1u16 << p.form.arc_count()
    };
    for s in 0..arc_sides {
        let s = if p.plane { sides } else { s as u8 };
        effort.evaluations += sweep(p, psi, s, &mut list);
    }
    // A group with few admissible seeds may hide a feasible region thinner than the sweep's
    // spacing next to its near misses.
    if !list.items.is_full() {
        let near = core::mem::take(&mut list.near);
        for (_, x) in near.iter() {
            if let Some(v) = escape(p, x, &mut effort.evaluations) {
                list.offer(v.objective, &v.x);
            }
        }
    }
    let mut best: Option<LocalSolution> = None;
    for x in list.items.iter().map(|(_, x)| x).chain(extra.iter()) {
        if let Some(sol) = refine(p, x, known, effort) {
            if best
                .as_ref()
                .is_none_or(|b| sol.eval.objective < b.eval.objective)
            {
                best = Some(sol);
            }
        }
    }
    best
}

/// Local solutions found so far for one problem (variables, objective), distinct.
type Basins = heapless::Vec<(Vars, f32), KNOWN_BASINS>;

/// Largest final step of a solve whose end marks a basin.
const STATIONARY: f32 = 1e-3;

/// Local solutions remembered per problem (beyond, new ones are not remembered).
const KNOWN_BASINS: usize = 12;

/// The SQP from `x`, stopped early in the basin of a solution in `known`; a new solution is
/// remembered there.
fn refine(p: &Problem, x: &Vars, known: &mut Basins, effort: &mut Effort) -> Option<LocalSolution> {
    let sol = sqp::solve(p, x, known)?;
    effort.iterations += sol.iterations;
    effort.evaluations += sol.evaluations;
    let (x, f) = (&sol.eval.x, sol.eval.objective);
    // Only a solve that ended stationary marks a basin: one stopped by its budget may lie on a
    // slope that a later start would descend further.
    let stationary = sol.status == SolveStatus::Converged && sol.step_norm < STATIONARY;
    let fresh = known
        .iter()
        .all(|(k, _)| (0..p.n).any(|j| libm::fabsf(x[j] - k[j]) >= sqp::BASIN));
    if stationary && fresh {
        // Full: the solution is simply not remembered.
        let _ = known.push((*x, f));
    }
    Some(sol)
}

/// Starts for `form` made from the best paths of the forms one segment shorter: the missing
/// segment is inserted with zero length, so a form never reports a worse path than a sub-form
/// it contains. Each start comes with its plane-mode side assignment.
#[inline(never)]
fn extension_starts(
    scenario: &Scenario,
    form: Form,
    previous: &[FormOutcome],
) -> heapless::Vec<(u8, Vars), EXTENSIONS> {
    let mut out = heapless::Vec::new();
    for o in previous
        .iter()
        .filter(|o| o.feasible && o.form.len() + 1 == form.len())
    {
        for gap in 0..form.len() {
            let shorter = (0..form.len()).filter(|&i| i != gap).map(|i| form.kind(i));
            if !shorter.eq((0..o.form.len()).map(|i| o.form.kind(i))) {
                continue;
            }
            let mut lengths = [0.0; MAX_CONTROL_DEGREE];
            let mut bevels = [0.0; MAX_CONTROL_DEGREE];
            for (k, i) in (0..form.len()).filter(|&i| i != gap).enumerate() {
                lengths[i] = o.segments[k].length;
                bevels[i] = o.segments[k].bevel_deg.to_radians();
            }
            let mut sides = 0u8;
            let mut facing_negative = false;
            let mut arc = 0;
            for i in 0..form.len() {
                if form.kind(i) == SegmentKind::Arc {
                    if libm::fabsf(bevels[i]) > 1.0 {
                        facing_negative = !facing_negative;
                    }
                    if facing_negative {
                        sides |= 1 << arc;
                    }
                    arc += 1;
                }
            }
            let p = Problem::new(scenario, form, sides);
            let mut x = [0.0; crate::optim::problem::MAX_VARS];
            x[0] = o.insertion.theta1_deg.to_radians();
            if !p.plane {
                x[1] = o.insertion.theta2_deg.to_radians();
            }
            for i in 0..form.len() {
                x[p.length_var(i)] = lengths[i] / p.radius;
                if let Some(k) = p.bevel_var(i) {
                    x[k] = bevels[i];
                }
            }
            if out.push((sides, x)).is_err() {
                return out;
            }
        }
    }
    out
}

/// Extension starts kept per form (forms one shorter times insertion places).
const EXTENSIONS: usize = 16;

/// Plans one form of `scenario`; `previous` holds the outcomes of forms already planned.
pub fn solve_form(scenario: &Scenario, form: Form, previous: &[FormOutcome]) -> FormOutcome {
    let mut effort = Effort::default();
    let mut best: Option<(Problem, LocalSolution)> = None;
    let extensions = extension_starts(scenario, form, previous);
    let mut extra: heapless::Vec<Vars, EXTENSIONS> = heapless::Vec::new();
    if scenario.options.workspace == Workspace::PlaneYz {
        for sides in 0..(1u16 << form.arc_count()) {
            let p = Problem::new(scenario, form, sides as u8);
            extra.clear();
            for (s, x) in extensions.iter() {
                if u16::from(*s) == sides {
                    // Same capacity as `extensions`.
                    let _ = extra.push(*x);
                }
            }
            let mut known = Basins::new();
            let sol = solve_group(&p, 0.0, sides as u8, &extra, &mut known, &mut effort);
            consider(p, sol, &mut best);
        }
    } else {
        // Every seed plane poses the same problem: its solutions are shared.
        let mut known = Basins::new();
        for k in 0..SPACE_PLANES {
            let psi = core::f32::consts::PI * k as f32 / SPACE_PLANES as f32;
            let p = Problem::new(scenario, form, 0);
            let sol = solve_group(&p, psi, 0, &[], &mut known, &mut effort);
            consider(p, sol, &mut best);
        }
        for (_, x) in extensions.iter() {
            let p = Problem::new(scenario, form, 0);
            let sol = refine(&p, x, &mut known, &mut effort);
            consider(p, sol, &mut best);
        }
    }
    match best {
        Some((p, sol)) => report(&p, &sol, &effort),
        None => infeasible(form, &effort),
    }
}

fn wrap_degrees(rad: f32) -> f32 {
    let mut d = rad.to_degrees() % 360.0;
    if d > 180.0 {
        d -= 360.0;
    } else if d <= -180.0 {
        d += 360.0;
    }
    d
}

/// The outcome of a refined path, with the numbers measured by the independent check.
#[inline(never)] // The check's buffers need not share the stack with the search's.
fn report(p: &Problem, sol: &LocalSolution, effort: &Effort) -> FormOutcome {
    let x = &sol.eval.x;
    let (t1, t2) = p.angles(x);
    let basis = entry_basis(p.scenario.entry.direction);
    let heading = insertion_frame(V3::zeros(), &basis, t1, t2).e3();
    let nominal: V3 = basis.column(2).into();
    let insertion = Insertion {
        theta1_deg: t1.to_degrees(),
        theta2_deg: t2.to_degrees(),
        tilt_deg: crate::fmath::acos(crate::fmath::clamp(heading.dot(&nominal), -1.0, 1.0))
            .to_degrees(),
        direction: [heading.x, heading.y, heading.z],
    };
    let lengths = p.lengths(x);
    let bevels = p.bevels(x);
    let mut segments = Segments::new();
    for i in 0..p.form.len() {
        let bevel = if p.form.kind(i) == SegmentKind::Arc {
            wrap_degrees(bevels[i])
        } else {
            0.0
        };
        // Capacity equals the longest form.
        let _ = segments.push(SegmentPlan {
            kind: p.form.kind(i),
            length: lengths[i],
            bevel_deg: bevel,
        });
    }
    let verdict = check(p.scenario, p.form, &insertion, &segments);
    let w = &p.scenario.weights;
    let penalty = if verdict.min_clearance > 0.0 {
        0.0
    } else {
        1e6
    };
    let objective = w.length * verdict.length
        + w.risk * verdict.risk
        + w.penalty * penalty
        + w.control * p.form.len() as f32;
    let status = if verdict.feasible {
        sol.status
    } else {
        SolveStatus::Infeasible
    };
    FormOutcome {
        form: p.form,
        status,
        feasible: verdict.feasible,
        length: verdict.length,
        risk: verdict.risk,
        penalty,
        objective: if verdict.feasible {
            objective
        } else {
            f32::INFINITY
        },
        min_clearance: verdict.min_clearance,
        target_error: verdict.target_error,
        insertion,
        segments,
        kkt_residual: sol.step_norm,
        iterations: effort.iterations,
        evaluations: effort.evaluations,
    }
}

fn infeasible(form: Form, effort: &Effort) -> FormOutcome {
    FormOutcome {
        iterations: effort.iterations,
        evaluations: effort.evaluations,
        ..FormOutcome::infeasible(form)
    }
}

/// Keeps the better of `best` and the solution of problem `p`.
fn consider<'a>(
    p: Problem<'a>,
    sol: Option<LocalSolution>,
    best: &mut Option<(Problem<'a>, LocalSolution)>,
) {
    if let Some(sol) = sol {
        if best
            .as_ref()
            .is_none_or(|(_, b)| sol.eval.objective < b.eval.objective)
        {
            *best = Some((p, sol));
        }
    }
}
