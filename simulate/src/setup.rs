//! What the three ways of running `needle simulate` share: the planned insertion, its
//! perturbation and seeds (a [`Setup`]), and how runs are collected, whoever executes them (open
//! loop, the in-process controller, a device): chunk by chunk, each run cut down to what the
//! outputs need ([`Keep`]), so that memory grows with `--runs` by a few numbers a run, not by
//! every run's path and steps.

use super::{prepare_keeping_reserve, run_seed, PlanBound, Prepared};
use anyhow::{anyhow, Result};
use needle_analysis::parallel;
use needle_scenario::voxels::VoxelJudge;
use needle_sim::{
    closed_loop_in, in_process, open_loop_in, ClosedLoopError, ClosedRun, Conditions, Controller,
    Perturbation, Planned, Run, TrackerFaults, WorldEffects,
};
use planner_core::steer::SteerConfig;
use planner_core::Scenario;
use std::sync::Arc;

/// Runs executed between two prunings of the paths kept for the plot.
const CHUNK: usize = 1024;

/// The insertion every run executes, and in which worlds.
pub struct Setup {
    /// The scenario (restricted to `--form`).
    pub scenario: Scenario,
    /// The plan and its schedule.
    pub prepared: Prepared,
    /// The planned path, to measure deviations from.
    pub planned: Planned,
    /// What every world draws from.
    pub perturbation: Perturbation,
    /// The effects beyond the perturbation (all off: today's world).
    pub effects: WorldEffects,
    /// The tracker's faults (closed loop).
    pub faults: TrackerFaults,
    /// The controller's settings (closed loop).
    pub config: SteerConfig,
    /// Number of runs.
    pub runs: usize,
    /// Seed of the first run.
    pub seed: u64,
    /// The collision bound the plan keeps, if any (a device plans under it too).
    pub bound: Option<PlanBound>,
    /// The curvature reserve the scenario asked for; `scenario` holds the one planned with,
    /// less where no path kept this much ([`prepare_keeping_reserve`]).
    pub reserve_asked: f32,
    /// The organs' voxels each run's true path is judged against, with `[[anatomy]]`.
    pub voxels: Option<Arc<VoxelJudge>>,
}

/// What is kept of each run beyond its figures.
#[derive(Clone, Copy, Debug, Default)]
pub struct Keep {
    /// Everything (`--detail`): draws, points and steps of every run.
    pub detail: bool,
    /// The paths of the runs among the first this many that reached the target (for the plot).
    pub paths: usize,
    /// The paths of the first this many runs stopped before the target, wherever they are (for
    /// the plot: the runs a reader looks for).
    pub stopped_paths: usize,
}

impl Keep {
    /// Cuts run `index` down to what is kept.
    fn trim(&self, index: usize, stopped: bool, run: &mut Run) {
        if !self.detail {
            run.steps = Vec::new();
            run.drawn.steps = Vec::new();
            // A stopped run's path is kept until the count of stopped runs is known, chunk by
            // chunk (`Setup::collect`).
            let drawn = if stopped {
                self.stopped_paths > 0
            } else {
                index < self.paths
            };
            if !drawn {
                run.points = Vec::new();
            }
        }
    }

    /// Cuts closed-loop run `index` down to what is kept.
    pub fn trim_closed(&self, index: usize, mut run: ClosedRun) -> ClosedRun {
        run.replan_evaluations = Vec::new();
        self.trim(index, run.stop_reason.is_some(), &mut run.run);
        run
    }
}

/// A run's record as collected: what it is, whether it stopped before the target.
pub trait Collected {
    /// The run's figures and what is kept of its path.
    fn run_mut(&mut self) -> &mut Run;
    /// The controller stopped it before the target.
    fn stopped(&self) -> bool;
}

impl Collected for Run {
    fn run_mut(&mut self) -> &mut Run {
        self
    }
    fn stopped(&self) -> bool {
        false
    }
}

impl Collected for ClosedRun {
    fn run_mut(&mut self) -> &mut Run {
        &mut self.run
    }
    fn stopped(&self) -> bool {
        self.stop_reason.is_some()
    }
}

impl Setup {
    /// Plans `scenario` and sets up `runs` worlds from `seed`.
    pub fn new(
        scenario: Scenario,
        perturbation: Perturbation,
        faults: TrackerFaults,
        runs: usize,
        seed: u64,
    ) -> Result<Setup> {
        Setup::bounded(scenario, perturbation, faults, runs, seed, None)
    }

    /// [`Setup::new`], the plan made under `bound` when given, keeping as much of the
    /// scenario's curvature reserve as a path allows (`scenario` then says how much).
    pub fn bounded(
        scenario: Scenario,
        perturbation: Perturbation,
        faults: TrackerFaults,
        runs: usize,
        seed: u64,
        bound: Option<&PlanBound>,
    ) -> Result<Setup> {
        perturbation.validate()?;
        let reserve_asked = scenario.options.curvature_reserve;
        let (scenario, prepared) = prepare_keeping_reserve(&scenario, bound)?;
        let planned = Planned::of(&scenario, &prepared.outcome);
        Ok(Setup {
            scenario,
            prepared,
            planned,
            perturbation,
            effects: WorldEffects::default(),
            faults,
            config: SteerConfig::DEFAULT,
            runs,
            seed,
            bound: bound.copied(),
            reserve_asked,
            voxels: None,
        })
    }

    /// Every run, chunk by chunk in the order of their indices: `chunk` executes the runs of
    /// the (index, seed) pairs it is given and trims each as `keep` says; the paths of stopped
    /// runs beyond `keep.stopped_paths` are dropped between chunks. The result is the same
    /// whatever the chunk size.
    pub fn collect<R: Collected>(
        &self,
        keep: &Keep,
        mut chunk: impl FnMut(&[(usize, u64)]) -> Result<Vec<R>>,
    ) -> Result<Vec<R>> {
        let mut out = Vec::with_capacity(self.runs);
        let mut stopped_drawn = 0;
        for start in (0..self.runs).step_by(CHUNK) {
            let items: Vec<(usize, u64)> = (start..self.runs.min(start + CHUNK))
                .map(|i| (i, run_seed(self.seed, i)))
                .collect();
            for mut r in chunk(&items)? {
                if r.stopped() && !keep.detail {
                    if stopped_drawn < keep.stopped_paths {
                        stopped_drawn += 1;
                    } else {
                        r.run_mut().points = Vec::new();
                    }
                }
                out.push(r);
            }
        }
        Ok(out)
    }

    /// Judges `run`'s true path against the organs' voxels, if there are any: a path that
    /// entered one collided, whatever the spheres say.
    pub fn judge(&self, run: &mut Run) {
        if let Some(j) = &self.voxels {
            let entered = j.entered(&run.points);
            run.entered_voxels = Some(entered);
            run.collided |= entered;
        }
    }

    /// The world the runs are simulated in: the perturbation, the effects and the faults.
    pub fn conditions(&self) -> Conditions<'_> {
        Conditions {
            perturbation: &self.perturbation,
            effects: &self.effects,
            faults: &self.faults,
        }
    }

    /// One run steered by `controller` (already started on the schedule) in the world of `seed`.
    pub fn steer<C: Controller>(
        &self,
        controller: &mut C,
        seed: u64,
    ) -> Result<ClosedRun, ClosedLoopError<C::Error>> {
        let world = self.conditions();
        closed_loop_in(
            &self.scenario,
            &self.planned,
            &self.prepared.schedule,
            &world,
            controller,
            seed,
        )
    }

    /// Every run executed by `one` (given its index and seed) on `threads` threads; the result
    /// is the same on any count.
    fn in_parallel<R: Collected + Send>(
        &self,
        keep: &Keep,
        threads: usize,
        done: impl Fn() + Sync,
        one: impl Fn(usize, u64) -> Result<R> + Sync,
    ) -> Result<Vec<R>> {
        self.collect(keep, |items| {
            parallel::map(items, threads, |&(i, seed)| one(i, seed), &done)
                .into_iter()
                .collect()
        })
    }

    /// Every run executed open loop on `threads` threads.
    pub fn open_loop(
        &self,
        keep: &Keep,
        threads: usize,
        done: impl Fn() + Sync,
    ) -> Result<Vec<Run>> {
        self.in_parallel(keep, threads, done, |i, seed| {
            let schedule = &self.prepared.schedule;
            let p = &self.perturbation;
            let (s, planned, e) = (&self.scenario, &self.planned, &self.effects);
            let mut run = open_loop_in(s, planned, schedule, p, e, seed)?;
            self.judge(&mut run);
            keep.trim(i, false, &mut run);
            Ok(run)
        })
    }

    /// Every run steered by the in-process controller on `threads` threads.
    pub fn closed_loop(
        &self,
        keep: &Keep,
        threads: usize,
        done: impl Fn() + Sync,
    ) -> Result<Vec<ClosedRun>> {
        self.in_parallel(keep, threads, done, |i, seed| {
            let mut ctl = in_process(&self.scenario, &self.prepared.schedule, &self.config)
                .map_err(|e| anyhow!("steering cannot start: {e}"))?;
            let mut run = self.steer(&mut ctl, seed).map_err(|e| anyhow!("{e}"))?;
            self.judge(&mut run.run);
            Ok(keep.trim_closed(i, run))
        })
    }
}
