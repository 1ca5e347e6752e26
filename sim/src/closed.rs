//! One closed-loop run: the world executes the controller's steps, the tracker measures the tip
//! after every piece, and each reading goes to the controller (in-process, or on a device over
//! the wire), whose reply may replace the steps or stop the insertion. Tracker faults (dropouts,
//! outliers, repeated and stale sequence numbers) are drawn from their own stream, so turning
//! them on does not change the tissue or the tracker's noise.

use crate::faults::TrackerFaults;
use crate::random::{seeded, Draw, SplitMix64};
use crate::reading::Measurement;
use crate::run::{finish, Planned, Run};
use crate::world::World;
use crate::world::WorldError;
use crate::{EffectsError, PerturbError, Perturbation, WorldEffects};
use planner_core::execute::schedule::{Schedule, Step};
use planner_core::model::kinematics::{Frame, V3};
use planner_core::steer::{
    Command, Pose, SteerConfig, SteerError, SteerReply, SteerStats, Steering, StopReason,
    TipMeasurement,
};
use planner_core::Scenario;
use serde::Serialize;
use std::ops::ControlFlow;

/// Offsets the fault stream from the physics stream of the same seed.
const FAULT_STREAM: u64 = 0x4641_554C_5453_2121;

/// What the controller on the other side of the readings is: the in-process [`Steering`] here; a
/// device behind the link is adapted to it by its user (this crate knows no transport).
pub trait Controller {
    /// Why a reading could not be answered (a link error, for a device).
    type Error;
    /// Answers one reading.
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, Self::Error>;
    /// The controller's counters.
    fn stats(&mut self) -> Result<SteerStats, Self::Error>;
}

impl Controller for Steering {
    type Error = std::convert::Infallible;
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, Self::Error> {
        Ok(Steering::update(self, m))
    }
    fn stats(&mut self) -> Result<SteerStats, Self::Error> {
        Ok(Steering::stats(self))
    }
}

/// A closed-loop run's figures: the run, why it stopped and the controller's counters.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ClosedRun {
    /// The run (target error, deviations, clearance, points).
    #[serde(flatten)]
    pub run: Run,
    /// Why the controller stopped; `None` when it reached the target. A run whose steps ran
    /// out without the controller's verdict counts as [`StopReason::Missed`].
    pub stop_reason: Option<StopReason>,
    /// How far the controller's estimate put the tip from the target when it stopped (mm;
    /// `None` without a verdict): the predicted miss, beside the run's true target error.
    pub predicted_miss_mm: Option<f32>,
    /// The controller's counters.
    pub stats: SteerStats,
    /// Path evaluations of each reading that replanned.
    #[serde(skip)]
    pub replan_evaluations: Vec<u32>,
}

/// Why a closed-loop run could not be made.
#[derive(Debug)]
pub enum ClosedLoopError<E> {
    /// The perturbation is invalid.
    Perturbation(PerturbError),
    /// A world effect is invalid.
    Effects(EffectsError),
    /// The controller could not start.
    Start(SteerError),
    /// The controller did not answer.
    Controller(E),
}

impl<E: std::fmt::Display> std::fmt::Display for ClosedLoopError<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ClosedLoopError::Perturbation(e) => write!(f, "{e}"),
            ClosedLoopError::Effects(e) => write!(f, "{e}"),
            ClosedLoopError::Start(e) => write!(f, "steering cannot start: {e}"),
            ClosedLoopError::Controller(e) => write!(f, "the controller did not answer: {e}"),
        }
    }
}

impl<E: std::fmt::Debug + std::fmt::Display> std::error::Error for ClosedLoopError<E> {}

/// The tracker between the world and the controller: numbers readings and injects faults (the
/// closed loop's, and the simulated lab's, so that both draw the same faults for a seed).
pub struct Tracker {
    faults: TrackerFaults,
    g: SplitMix64,
    seq: u32,
    dropout_until: f32,
    depth: f32,
    previous: Option<TipMeasurement>,
}

impl Tracker {
    /// The tracker of the run of `seed`, injecting `faults` (from their own stream).
    pub fn new(faults: &TrackerFaults, seed: u64) -> Tracker {
        Tracker {
            faults: *faults,
            g: seeded(seed ^ FAULT_STREAM),
            seq: 0,
            dropout_until: f32::NEG_INFINITY,
            depth: 0.0,
            previous: None,
        }
    }

    /// The readings one world measurement turns into: the reading itself, and maybe a repeat or
    /// an old one after it (marked `true`: the tracker's fault, whose answers are not acted on).
    pub fn readings(&mut self, m: &Measurement) -> Vec<(TipMeasurement, bool)> {
        self.seq += 1;
        let f = self.faults;
        let mut pose = Some(Pose {
            position: m.position,
            heading: m.heading,
            bevel: m.roll_seen.then_some(m.bevel),
        });
        let pushed = (m.depth_mm - self.depth).max(0.0);
        self.depth = m.depth_mm;
        if f.dropout_rate > 0.0 && self.g.unit() < f64::from(f.dropout_rate * pushed) {
            self.dropout_until = self.dropout_until.max(m.depth_mm + f.dropout_mm);
        }
        if m.depth_mm < self.dropout_until {
            pose = None;
        }
        if let Some(p) = pose.as_mut() {
            if f.outlier_rate > 0.0 && self.g.unit() < f64::from(f.outlier_rate) {
                let dir = [0; 3].map(|_| self.g.normal(1.0) as f32);
                let n = dir.iter().map(|v| v * v).sum::<f32>().sqrt().max(1e-6);
                for (x, d) in p.position.iter_mut().zip(dir) {
                    *x += d / n * f.outlier_mm;
                }
            }
        }
        let reading = TipMeasurement {
            seq: self.seq,
            depth_mm: m.depth_mm,
            base_deg: m.base_deg,
            pose,
            target: pose.and(m.target_seen.then_some(m.target)),
        };
        let mut out = vec![(reading, false)];
        if f.repeat_rate > 0.0 && self.g.unit() < f64::from(f.repeat_rate) {
            out.push((reading, true));
        }
        if let Some(old) = self.previous {
            if f.stale_rate > 0.0 && self.g.unit() < f64::from(f.stale_rate) {
                out.push((old, true));
            }
        }
        self.previous = Some(reading);
        out
    }
}

/// Starts the in-process controller for `schedule`.
pub fn in_process(
    scenario: &Scenario,
    schedule: &Schedule,
    config: &SteerConfig,
) -> Result<Steering, SteerError> {
    Steering::start(scenario, schedule, config)
}

/// The world a run is made in: the perturbation, the world's effects and the tracker's faults.
#[derive(Clone, Copy, Debug)]
pub struct Conditions<'a> {
    /// The perturbation of the planner's own model.
    pub perturbation: &'a Perturbation,
    /// The effects beyond it (all off: today's world).
    pub effects: &'a WorldEffects,
    /// The tracker's faults.
    pub faults: &'a TrackerFaults,
}

/// Runs one closed-loop insertion in the world of `seed`, steered by `controller` (started on
/// `schedule`).
pub fn closed_loop<C: Controller>(
    scenario: &Scenario,
    planned: &Planned,
    schedule: &Schedule,
    p: &Perturbation,
    faults: &TrackerFaults,
    controller: &mut C,
    seed: u64,
) -> Result<ClosedRun, ClosedLoopError<C::Error>> {
    let world = Conditions {
        perturbation: p,
        effects: &WorldEffects::default(),
        faults,
    };
    closed_loop_in(scenario, planned, schedule, &world, controller, seed)
}

/// [`closed_loop`] in a world with effects.
pub fn closed_loop_in<C: Controller>(
    scenario: &Scenario,
    planned: &Planned,
    schedule: &Schedule,
    conditions: &Conditions<'_>,
    controller: &mut C,
    seed: u64,
) -> Result<ClosedRun, ClosedLoopError<C::Error>> {
    let unseen = |_: &Seen<'_, C>| {};
    closed_loop_observed(
        scenario, planned, schedule, conditions, controller, seed, unseen,
    )
}

/// What an observer of a closed-loop run sees after each reading the controller answered (a
/// tracker's injected repeat or old reading is not shown).
pub struct Seen<'a, C> {
    /// The reading the controller was given.
    pub reading: &'a TipMeasurement,
    /// The true tip frame when the reading was taken.
    pub tip: &'a Frame,
    /// The true target (where the tissue has carried it) when the reading was taken.
    pub target: V3,
    /// The step the world was executing.
    pub step: &'a Step,
    /// The controller, having answered the reading.
    pub controller: &'a C,
}

/// [`closed_loop_in`], `observe` called after each reading the controller answered. Observing
/// changes nothing: the run is the same, bit for bit.
pub fn closed_loop_observed<C: Controller>(
    scenario: &Scenario,
    planned: &Planned,
    schedule: &Schedule,
    conditions: &Conditions<'_>,
    controller: &mut C,
    seed: u64,
    mut observe: impl FnMut(&Seen<'_, C>),
) -> Result<ClosedRun, ClosedLoopError<C::Error>> {
    let (p, faults) = (conditions.perturbation, conditions.faults);
    let mut world = World::with_effects(scenario, schedule, p, conditions.effects, seed).map_err(
        |e| match e {
            WorldError::Perturbation(e) => ClosedLoopError::Perturbation(e),
            WorldError::Effects(e) => ClosedLoopError::Effects(e),
        },
    )?;
    let mut tracker = Tracker::new(faults, seed);
    let mut steps: Vec<Step> = schedule.steps.to_vec();
    let mut stop: Option<StopReason> = None;
    let mut predicted_miss_mm = None;
    let mut failure: Option<C::Error> = None;
    let mut replan_evaluations = Vec::new();
    // Each continuation has at most MAX_STEPS steps and each reading may replace it; the world
    // ends the loop when the steps run out, the controller when it stops.
    'continuations: loop {
        let mut next: Option<Vec<Step>> = None;
        for step in &steps {
            world.execute_seen(step, |m, tip, target| {
                for (reading, injected) in tracker.readings(m) {
                    let reply = match controller.update(&reading) {
                        Ok(r) => r,
                        Err(e) => {
                            failure = Some(e);
                            return ControlFlow::Break(());
                        }
                    };
                    if injected {
                        continue; // the tracker's repeat or old reading: nothing new to act on
                    }
                    let (reading, controller) = (&reading, &*controller);
                    observe(&Seen {
                        reading,
                        tip,
                        target,
                        step,
                        controller,
                    });
                    if reply.replanned {
                        replan_evaluations.push(reply.evaluations);
                    }
                    match reply.command {
                        Command::Continue => {}
                        Command::Replace(s) => next = Some(s.to_vec()),
                        Command::Stop(reason) => {
                            stop = Some(reason);
                            predicted_miss_mm =
                                Some(reply.predicted_error_mm).filter(|e| e.is_finite());
                        }
                    }
                }
                if stop.is_some() || next.is_some() {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            });
            if let Some(e) = failure.take() {
                return Err(ClosedLoopError::Controller(e));
            }
            if stop.is_some() {
                break 'continuations;
            }
            if next.is_some() {
                break;
            }
        }
        match next {
            Some(s) => steps = s,
            None => break,
        }
    }
    let stats = controller.stats().map_err(ClosedLoopError::Controller)?;
    let ended = Ended {
        stop,
        predicted_miss_mm,
        stats,
        replan_evaluations,
    };
    Ok(ended.run(&world, planned, seed))
}

/// How a closed loop ended, as its controller said.
pub(crate) struct Ended {
    /// The controller's stop; `None`: the steps ran out first.
    pub stop: Option<StopReason>,
    /// Its predicted miss at the stop.
    pub predicted_miss_mm: Option<f32>,
    /// Its counters.
    pub stats: SteerStats,
    /// Path evaluations of each reading that replanned.
    pub replan_evaluations: Vec<u32>,
}

impl Ended {
    /// The run in `world` that ended so.
    pub(crate) fn run(self, world: &World, planned: &Planned, seed: u64) -> ClosedRun {
        ClosedRun {
            run: finish(world, planned, seed),
            stop_reason: match self.stop {
                Some(StopReason::TargetReached) => None,
                Some(reason) => Some(reason),
                None => Some(StopReason::Missed),
            },
            predicted_miss_mm: self.predicted_miss_mm,
            stats: self.stats,
            replan_evaluations: self.replan_evaluations,
        }
    }
}
