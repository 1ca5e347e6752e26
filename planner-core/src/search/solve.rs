//! "Path classification": the best path of one form.
//!
//! For every side assignment of the arcs (plane mode) or every seed plane (3-D), seeds are moved
//! onto the target and scored; the best distinct ones of the whole form (in plane mode, of each
//! side assignment's best few) are refined by the SQP, best first; the best refined path is
//! re-checked by [`crate::check`] and reported with the numbers the check measured.

use crate::check::check;
use crate::model::form::{Form, SegmentKind};
use crate::model::kinematics::{entry_basis, insertion_frame, V3};
use crate::model::scenario::{Scenario, Workspace};
use crate::optim::problem::{Problem, Vars};
use crate::optim::sqp::{self, LocalSolution, SolveFailure};
use crate::report::{FormOutcome, Insertion, SegmentPlan, Segments, SolveStatus};
use crate::search::escape::escape;
use crate::search::seeds::{sweep, SeedSink};
use crate::search::starts::{extension_starts, planned_without};
use crate::search::sweep_plane::seed_plane_turns;

/// Seed planes tried in 3-D (turns of the plane about the entry-target line over half a turn).
pub const SPACE_PLANES: usize = 8;
/// Distinct seeds kept per side assignment in plane mode (the form's best of them are refined).
pub const REFINED_PER_GROUP: usize = 3;
/// Near misses moved out of their obstacles per group, when the group has room for more seeds.
pub const NEAR_MISSES_PER_GROUP: usize = 2;

/// Distinct seeds refined per form in 3-D, gathered over all its seed planes.
pub const SPACE_REFINED: usize = 16;
/// Near misses moved out of their obstacles per form in 3-D.
pub const SPACE_NEAR_MISSES: usize = 4;

/// The best few admissible seeds, kept distinct, and the best few near misses. One type with
/// run-time limits serves both workspaces (one copy of its code in the firmware).
struct Shortlist {
    items: heapless::Vec<(f32, Vars), SPACE_REFINED>,
    /// The near misses that cut least into obstacles (their smallest clearance, variables).
    near: heapless::Vec<(f32, Vars), SPACE_NEAR_MISSES>,
    /// How many seeds and near misses are kept.
    limits: (usize, usize),
    /// Variables compared when telling seeds apart.
    n: usize,
    /// An objective no seed of use reaches (that of seeds already chosen elsewhere).
    ceiling: f32,
}

impl Shortlist {
    /// Keeps up to `seeds` seeds and `near_misses` near misses (at most the capacities).
    fn new(n: usize, seeds: usize, near_misses: usize) -> Self {
        Shortlist {
            items: heapless::Vec::new(),
            near: heapless::Vec::new(),
            limits: (seeds.min(SPACE_REFINED), near_misses.min(SPACE_NEAR_MISSES)),
            n,
            ceiling: f32::INFINITY,
        }
    }

    /// Moves the near misses out of their obstacles when the shortlist has room for more seeds:
    /// a search with few admissible seeds may hide a feasible region thinner than the sweep's
    /// spacing next to them.
    fn escape_near_misses(&mut self, p: &Problem, effort: &mut Effort) {
        if self.items.len() >= self.limits.0 {
            return;
        }
        let near = core::mem::take(&mut self.near);
        for (_, x) in near.iter() {
            if let Some(v) = escape(p, x, &mut effort.evaluations) {
                self.offer(v.objective, &v.x);
            }
        }
    }

    /// The seeds, best first (their refinement then finds the best basins before the others).
    fn sorted(&mut self) -> &[(f32, Vars)] {
        sort_by_objective(&mut self.items, |s| s.0);
        &self.items
    }
}

impl SeedSink for Shortlist {
    fn bound(&self) -> f32 {
        if self.items.len() < self.limits.0 {
            return self.ceiling;
        }
        let worst = self
            .items
            .iter()
            .map(|(f, _)| *f)
            .fold(f32::NEG_INFINITY, f32::max);
        crate::fmath::min(worst, self.ceiling)
    }

    fn offer(&mut self, objective: f32, at: &Vars) {
        keep_best(
            self.items.as_mut_view(),
            self.limits.0,
            objective,
            at,
            self.n,
        );
    }

    fn near_miss(&mut self, min_clearance: f32, x: &dyn Fn() -> Option<Vars>) {
        let worst = self
            .near
            .iter()
            .map(|(c, _)| -*c)
            .fold(f32::NEG_INFINITY, f32::max);
        if self.near.len() >= self.limits.1 && -min_clearance >= worst {
            return;
        }
        if let Some(x) = x() {
            keep_best(
                self.near.as_mut_view(),
                self.limits.1,
                -min_clearance,
                &x,
                self.n,
            );
        }
    }
}

/// Keeps in `items` the distinct points of lowest `key`: a point near one already kept replaces it
/// if lower, otherwise it takes the place of the highest when that is higher.
fn keep_best(
    items: &mut heapless::vec::VecView<(f32, Vars)>,
    limit: usize,
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
    if make_room(items, limit, key, |item| item.0) {
        // Room was made.
        let _ = items.push((key, *at));
    }
}

/// Whether an item of `key` belongs among the `limit` lowest of `items` (by `key_of`): true when
/// there is room, or after the highest, if higher than `key`, is removed to make it.
fn make_room<T>(
    items: &mut heapless::vec::VecView<T>,
    limit: usize,
    key: f32,
    key_of: impl Fn(&T) -> f32,
) -> bool {
    if items.len() < limit.min(items.capacity()) {
        return true;
    }
    let worst = (0..items.len())
        .max_by(|&a, &b| key_of(&items[a]).total_cmp(&key_of(&items[b])))
        .unwrap_or(0);
    if items.is_empty() || key >= key_of(&items[worst]) {
        return false;
    }
    items.swap_remove(worst);
    true
}

/// Sorts a shortlist by `objective`, lowest first (ties keep their order). An insertion sort:
/// the lists hold at most 16 seeds, and `core`'s sorts cost 12 KiB of firmware and a panic path.
fn sort_by_objective<T>(items: &mut [T], objective: impl Fn(&T) -> f32) {
    for i in 1..items.len() {
        let mut j = i;
        while j > 0
            && objective(&items[j - 1])
                .total_cmp(&objective(&items[j]))
                .is_gt()
        {
            items.swap(j - 1, j);
            j -= 1;
        }
    }
}

/// Effort spent on a form.
#[derive(Default)]
struct Effort {
    iterations: u32,
    evaluations: u32,
}

/// Local solutions found so far for one problem and the iterates that led to them (see
/// [`sqp::solve`]).
type Basins = heapless::Vec<(Vars, f32), KNOWN_BASINS>;

/// Points remembered per problem (beyond, new ones are not remembered).
const KNOWN_BASINS: usize = 24;

/// The SQP from `x`, stopped early in a basin `known` holds, which it adds to.
/// A start that cannot be made feasible is skipped; its effort is not counted.
fn refine(
    p: &Problem,
    x: &Vars,
    known: &mut Basins,
    effort: &mut Effort,
) -> Result<LocalSolution, SolveFailure> {
    let sol = sqp::solve(p, x, known.as_mut_view());
    if let Ok(sol) = &sol {
        effort.iterations += sol.iterations;
        effort.evaluations += sol.evaluations;
    }
    sol
}

/// Plans one form of `scenario`; `previous` holds the outcomes of forms already planned.
pub fn solve_form(scenario: &Scenario, form: Form, previous: &[FormOutcome]) -> FormOutcome {
    let mut effort = Effort::default();
    let extensions = extension_starts(scenario, form, previous);
    let search = FormSearch {
        scenario,
        form,
        planned_without: planned_without(form, previous),
        extensions: &extensions,
    };
    if scenario.options.workspace == Workspace::PlaneYz {
        search.plane(&mut effort)
    } else {
        search.space(&mut effort)
    }
}

/// What the search of one form starts from.
struct FormSearch<'a> {
    scenario: &'a Scenario,
    form: Form,
    /// Bit i set: the form without its line i was planned already (its sweep is left out).
    planned_without: u8,
    /// Starts carried over from the shorter forms already planned, by side assignment.
    extensions: &'a [(u8, Vars)],
}

impl FormSearch<'_> {
    /// Plane mode: every side assignment is its own problem. Each is swept into its own shortlist
    /// (its near misses escaped when it has room), the best seeds of all of them are refined
    /// together, and each side assignment's extension starts are refined as well.
    fn plane(&self, effort: &mut Effort) -> FormOutcome {
        let groups = 1u16 << self.form.arc_count();
        let mut chosen: heapless::Vec<SidedSeed, PLANE_REFINED> = heapless::Vec::new();
        for sides in 0..groups {
            let p = Problem::new(self.scenario, self.form, sides as u8);
            let mut list = Shortlist::new(p.n, REFINED_PER_GROUP, NEAR_MISSES_PER_GROUP);
            if chosen.is_full() {
                list.ceiling = chosen.iter().map(|s| s.0).fold(f32::NEG_INFINITY, f32::max);
            }
            effort.evaluations += sweep(&p, 0.0, sides as u8, self.planned_without, &mut list);
            list.escape_near_misses(&p, effort);
            for (f, x) in list.items.iter() {
                choose(&mut chosen, (*f, sides as u8, *x));
            }
        }
        sort_by_objective(&mut chosen, |s| s.0);
        let mut best: Option<(u8, LocalSolution)> = None;
        for sides in 0..groups {
            let sides = sides as u8;
            let seeds = chosen.iter().filter(|s| s.1 == sides).map(|s| &s.2);
            let extra = self
                .extensions
                .iter()
                .filter(|s| s.0 == sides)
                .map(|s| &s.1);
            let mut starts = extra.chain(seeds).peekable();
            if starts.peek().is_none() {
                continue;
            }
            let p = Problem::new(self.scenario, self.form, sides);
            let mut known = Basins::new();
            let mut group_best: Option<LocalSolution> = None;
            for x in starts {
                keep_lower(&mut group_best, refine(&p, x, &mut known, effort));
            }
            consider(sides, group_best, &mut best);
        }
        // The best group's problem made again rather than kept: each holds a broad phase over
        // the spheres, and the device's stack would hold three.
        match best {
            Some((sides, sol)) => {
                report(&Problem::new(self.scenario, self.form, sides), &sol, effort)
            }
            None => infeasible(self.form, effort),
        }
    }

    /// 3-D: every seed plane poses the same problem, so the seeds of all planes compete for one
    /// shortlist (seeds of neighbouring planes often lie in one basin) and the solutions found are
    /// shared.
    fn space(&self, effort: &mut Effort) -> FormOutcome {
        let p = Problem::new(self.scenario, self.form, 0);
        let mut list = Shortlist::new(p.n, SPACE_REFINED, SPACE_NEAR_MISSES);
        let mut turns = [0.0f32; SPACE_PLANES];
        let (planes, banded) = seed_plane_turns(&p, SPACE_PLANES, &mut turns);
        for &psi in &turns[..planes] {
            for sides in 0..(1u16 << self.form.arc_count()) {
                effort.evaluations += sweep(&p, psi, sides as u8, self.planned_without, &mut list);
            }
        }
        list.escape_near_misses(&p, effort);
        let mut known = Basins::new();
        let mut best: Option<LocalSolution> = None;
        // With the heading fixed or the cone narrow, the planar seeds come from the few planes
        // that hold the axis or cross the cone, while the shortest paths often bend out of them
        // from the first arc on: the seeds are tried again with their first arc rolled about
        // the heading. (One call site of the solver: the firmware's flash holds one copy.)
        let first_bevel = (0..self.form.len()).find_map(|i| p.bevel_var(i));
        let rolls = match first_bevel {
            Some(_) if banded || p.heading_fixed() => FIRST_ARC_ROLLS,
            _ => 1,
        };
        let seeds = list.sorted();
        for roll in 0..rolls {
            let extensions: &[(u8, Vars)] = if roll == 0 { self.extensions } else { &[] };
            let starts = extensions
                .iter()
                .map(|(_, x)| x)
                .chain(seeds.iter().map(|(_, x)| x));
            for x in starts {
                let mut x = *x;
                if let Some(k) = first_bevel.filter(|_| roll > 0) {
                    x[k] += core::f32::consts::TAU * roll as f32 / FIRST_ARC_ROLLS as f32;
                }
                keep_lower(&mut best, refine(&p, &x, &mut known, effort));
            }
        }
        match best {
            Some(sol) => report(&p, &sol, effort),
            None => infeasible(self.form, effort),
        }
    }
}

/// Rolls of a seed's first arc tried, its own included (evenly over a turn), when the heading is
/// fixed or the cone narrow.
const FIRST_ARC_ROLLS: usize = 6;

/// Seeds refined per form in plane mode: the best of every side assignment's shortlist.
pub const PLANE_REFINED: usize = 8;

/// A seed chosen for refinement in plane mode: objective, side assignment, variables.
type SidedSeed = (f32, u8, Vars);

/// Keeps in `chosen` the `PLANE_REFINED` seeds of lowest objective.
fn choose(chosen: &mut heapless::Vec<SidedSeed, PLANE_REFINED>, seed: SidedSeed) {
    if make_room(chosen.as_mut_view(), PLANE_REFINED, seed.0, |s| s.0) {
        // Room was made.
        let _ = chosen.push(seed);
    }
}

/// Keeps the lower of `best` and `sol`.
// One copy for both workspaces' loops (the firmware's flash).
#[inline(never)]
fn keep_lower(best: &mut Option<LocalSolution>, sol: Result<LocalSolution, SolveFailure>) {
    if let Ok(sol) = sol {
        if best
            .as_ref()
            .is_none_or(|b| sol.eval.objective < b.eval.objective)
        {
            *best = Some(sol);
        }
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
        kkt_residual: sol.kkt_residual,
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

/// Keeps the better of `best` and the solution of side assignment `sides`.
fn consider(sides: u8, sol: Option<LocalSolution>, best: &mut Option<(u8, LocalSolution)>) {
    if let Some(sol) = sol {
        if best
            .as_ref()
            .is_none_or(|(_, b)| sol.eval.objective < b.eval.objective)
        {
            *best = Some((sides, sol));
        }
    }
}

#[cfg(test)]
mod tests;
