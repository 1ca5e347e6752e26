//! The steering controller's state machine: readings in, commands out.

use super::replan::{predict_with, replan, segments_of, Prediction, ReplanInput};
use super::{
    Command, Reading, SteerConfig, SteerError, SteerReply, SteerStats, StopReason, TipMeasurement,
    REPLAN_DEFER_PER_MM, STEER_MARGIN_SDS,
};
use crate::estimate::target::TargetFix;
use crate::estimate::Estimate;
use crate::execute::nominal::posture_frame;
use crate::execute::schedule::{resized_step, Op, Schedule, Step, Steps, MAX_STEPS};
use crate::model::broad::{kept_tree, KeptTree};
use crate::model::form::SegmentKind;
use crate::model::kinematics::V3;
use crate::model::scenario::{Obstacles, Scenario};

/// Progress within a step counts as done this close to its end (mm, degrees): the robot's
/// counters add the pieces of a push in f32.
const DONE_SLACK: f32 = 1e-3;

/// Insertion left (mm) within which a reading no longer re-plans the continuation's forms, only
/// trims the last push ([`Steering::trimmed`]) or takes the closest approach: the needle bends
/// at most ahead² / 2r there (0.03 mm at 63.7 mm), less than the tracker resolves, while each
/// form tried costs a solve; at the end of a 256-sphere insertion steered with a reserve, one
/// reading tried ten (3.03 M instructions on the device, over its 1 M budget per reading).
const ONLY_TRIM_WITHIN_MM: f32 = 2.0;

/// A closest approach replaces a continuation that no longer reaches only if it predicts a miss
/// at most this share of the continuation's: a small gain is not worth the turn.
const CLOSER_BY: f32 = 0.95;

/// The closed-loop controller of one insertion (see the [module](super) documentation).
#[derive(Clone, Debug)]
pub struct Steering {
    scenario: Scenario,
    /// The tree over the scenario's spheres, built once for the predictions of every reading
    /// (none unless [`worth_a_tree`](crate::model::broad::worth_a_tree)).
    broad: KeptTree,
    config: SteerConfig,
    estimate: Estimate,
    steps: Steps,
    end_depth: [f32; MAX_STEPS],
    end_base: [f32; MAX_STEPS],
    cursor: usize,
    depth: f32,
    base: f32,
    last_fix_depth: f32,
    /// Depth of the last replan: a reading without insertion since (after a turn) re-plans
    /// only when the continuation has become unsafe.
    last_replan_depth: f32,
    /// The last replan tried only the turn made early, refused: the next tries the rest. One
    /// reading's work is either, not both (the device answers a reading within its budget), and
    /// a continuation that keeps its margin loses nothing by waiting a reading.
    early_refused: bool,
    last_kind: Option<SegmentKind>,
    /// The last reading came during a spun line: its bevel direction is meaningless.
    spinning: bool,
    last_seq: Option<u32>,
    last_reply: Option<SteerReply>,
    stopped: Option<StopReason>,
    stats: SteerStats,
}

fn finite3(a: &[f32; 3]) -> bool {
    a.iter().all(|v| v.is_finite())
}

fn v3(a: [f32; 3]) -> V3 {
    V3::new(a[0], a[1], a[2])
}

impl Steering {
    /// Starts steering `schedule` (the plan's motor steps) in `scenario`, the needle set at the
    /// schedule's posture with nothing inserted yet.
    pub fn start(
        scenario: &Scenario,
        schedule: &Schedule,
        config: &SteerConfig,
    ) -> Result<Steering, SteerError> {
        scenario.validate().map_err(SteerError::Scenario)?;
        if !config.is_valid() {
            return Err(SteerError::BadConfig);
        }
        if schedule.steps.is_empty() {
            return Err(SteerError::EmptySchedule);
        }
        let tip = posture_frame(scenario, schedule);
        let estimate = Estimate::new(tip, v3(scenario.target.position), &config.noise);
        // The scenario field by field, its obstacles pushed in place: a clone passes the list
        // (16 bytes a sphere) through temporaries on the device's stack.
        let mut s = Steering {
            scenario: Scenario {
                obstacles: Obstacles::new(),
                ..*scenario
            },
            broad: kept_tree(&scenario.obstacles),
            config: *config,
            estimate,
            steps: Steps::new(),
            end_depth: [0.0; MAX_STEPS],
            end_base: [0.0; MAX_STEPS],
            cursor: 0,
            depth: 0.0,
            base: 0.0,
            last_fix_depth: 0.0,
            last_replan_depth: f32::NEG_INFINITY,
            early_refused: false,
            last_kind: None,
            spinning: false,
            last_seq: None,
            last_reply: None,
            stopped: None,
            stats: SteerStats::default(),
        };
        // Cannot fail: the same capacity.
        let _ = s.scenario.obstacles.extend_from_slice(&scenario.obstacles);
        s.issue(&schedule.steps);
        Ok(s)
    }

    /// The current estimate.
    pub fn estimate(&self) -> &Estimate {
        &self.estimate
    }

    /// The steps being executed (from the last replan on).
    pub fn steps(&self) -> &[Step] {
        &self.steps
    }

    /// The scenario steered in (its driver's speeds and needle are a board's soft limits).
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The counters so far.
    pub fn stats(&self) -> SteerStats {
        self.stats
    }

    /// Why the controller stopped, once it has.
    pub fn stopped(&self) -> Option<StopReason> {
        self.stopped
    }

    /// Makes `steps` the continuation, starting at the robot's progress now.
    fn issue(&mut self, steps: &[Step]) {
        self.steps.clear();
        let (mut depth, mut base) = (self.depth, self.base);
        for (i, step) in steps.iter().take(MAX_STEPS).enumerate() {
            match step.op {
                Op::Rotate { angle_deg } => base += angle_deg,
                op => depth += op.inserted_mm(),
            }
            self.end_depth[i] = depth;
            self.end_base[i] = base;
            // Cannot fail: at most MAX_STEPS are taken.
            let _ = self.steps.push(*step);
        }
        self.cursor = 0;
    }

    fn done(&self, i: usize) -> bool {
        let depth_done = self.depth >= self.end_depth[i] - DONE_SLACK;
        match self.steps[i].op {
            Op::Rotate { .. } => {
                depth_done && libm::fabsf(self.base - self.end_base[i]) <= DONE_SLACK
            }
            _ => depth_done,
        }
    }

    /// The insertion in progress (the first not yet done): its segment's kind and radius, and
    /// whether the shaft spins during it (a spun line, a duty-cycled push).
    fn insertion_in_progress(&self) -> (SegmentKind, f32, bool) {
        let radius = self.scenario.needle.curvature_radius;
        for step in self.steps.iter().skip(self.cursor) {
            if let Some((kind, _, r)) = step.op.segment(radius) {
                return (kind, r, !matches!(step.op, Op::Insert { .. }));
            }
        }
        (self.last_kind.unwrap_or(SegmentKind::Line), radius, true)
    }

    /// What remains of the continuation: the step in progress cut to what is left of it.
    fn remaining(&self) -> Steps {
        let mut out = Steps::new();
        for i in self.cursor..self.steps.len() {
            let mut step = self.steps[i];
            if i == self.cursor {
                let left = match step.op {
                    Op::Rotate { .. } => self.end_base[i] - self.base,
                    _ => (self.end_depth[i] - self.depth).max(0.0),
                };
                // A validated driver always has a step for what is left.
                step = resized_step(&self.scenario.driver, &step, left).unwrap_or(step);
            }
            let _ = out.push(step);
        }
        out
    }

    fn radius(&self) -> f32 {
        self.scenario.needle.curvature_radius / self.estimate.factor
    }

    fn predict(&self, steps: &[Step]) -> Prediction {
        predict_with(
            &self.scenario,
            self.broad.first(),
            &self.estimate.tip,
            steps,
            self.radius(),
            self.estimate.target,
        )
    }

    fn reply(&mut self, seq: u32, command: Command, reading: Reading) -> SteerReply {
        if let Command::Stop(reason) = command {
            self.stopped = Some(reason);
        }
        let reply = SteerReply {
            seq,
            command,
            reading,
            replanned: false,
            predicted_error_mm: f32::NAN,
            predicted_clearance_mm: f32::NAN,
            evaluations: 0,
        };
        self.last_reply = Some(reply.clone());
        reply
    }

    /// The end of the continuation: reached or missed, by the estimate's distance to the target.
    #[inline(never)]
    fn verdict(&mut self, seq: u32, reading: Reading) -> SteerReply {
        let miss = (self.estimate.tip.p - self.estimate.target).norm();
        let reason = if miss <= self.config.reach_tolerance_mm {
            StopReason::TargetReached
        } else {
            StopReason::Missed
        };
        let mut reply = self.reply(seq, Command::Stop(reason), reading);
        reply.predicted_error_mm = miss;
        self.last_reply = Some(reply.clone());
        reply
    }

    /// Applies one reading and says what to do next. Never panics; a reading that cannot be
    /// trusted is rejected or stops the insertion with the reason.
    pub fn update(&mut self, m: &TipMeasurement) -> SteerReply {
        match self.last_seq {
            Some(last) if m.seq == last => {
                self.stats.repeated += 1;
                if let Some(r) = &self.last_reply {
                    let mut r = r.clone();
                    r.reading = Reading::Repeated;
                    return r;
                }
            }
            Some(last) if m.seq < last => {
                self.stats.stale += 1;
                let command = match self.stopped {
                    Some(reason) => Command::Stop(reason),
                    None => Command::Continue,
                };
                let mut r = SteerReply {
                    seq: m.seq,
                    command,
                    reading: Reading::Stale,
                    replanned: false,
                    predicted_error_mm: f32::NAN,
                    predicted_clearance_mm: f32::NAN,
                    evaluations: 0,
                };
                if let Some(last) = &self.last_reply {
                    r.predicted_error_mm = last.predicted_error_mm;
                    r.predicted_clearance_mm = last.predicted_clearance_mm;
                }
                return r;
            }
            _ => {}
        }
        self.last_seq = Some(m.seq);
        if let Some(reason) = self.stopped {
            return self.reply(m.seq, Command::Stop(reason), Reading::NoFix);
        }
        self.stats.readings += 1;
        let progress_ok = m.depth_mm.is_finite()
            && m.base_deg.is_finite()
            && m.depth_mm >= self.depth - DONE_SLACK;
        if !progress_ok {
            let stop = Command::Stop(StopReason::BadMeasurement);
            return self.reply(m.seq, stop, Reading::Outlier);
        }
        self.predict_motion(m);
        let reading = self.fuse(m);
        if self.depth - self.last_fix_depth > self.config.max_gap_mm {
            return self.reply(m.seq, Command::Stop(StopReason::TrackingLost), reading);
        }
        if self.cursor >= self.steps.len() {
            return self.verdict(m.seq, reading);
        }
        self.steer(m.seq, reading)
    }

    /// The kinematic prediction from the robot's progress since the last reading.
    fn predict_motion(&mut self, m: &TipMeasurement) {
        let turned = m.base_deg - self.base;
        if turned != 0.0 {
            self.estimate.rotated(turned, m.depth_mm);
        }
        let pushed = m.depth_mm - self.depth;
        self.spinning = false;
        if pushed > 0.0 {
            let (kind, radius, spinning) = self.insertion_in_progress();
            if kind == SegmentKind::Arc && self.last_kind != Some(SegmentKind::Arc) {
                self.estimate.new_arc();
            }
            self.estimate.advanced(kind, pushed, radius);
            self.last_kind = Some(kind);
            self.spinning = spinning;
            if spinning {
                self.estimate.spinning(m.depth_mm);
            }
        }
        self.depth = self.depth.max(m.depth_mm);
        self.base = m.base_deg;
        while self.cursor < self.steps.len() && self.done(self.cursor) {
            if matches!(
                self.steps[self.cursor].op,
                Op::InsertSpin { .. } | Op::InsertDuty { .. }
            ) {
                self.estimate.spun(self.depth);
            }
            self.cursor += 1;
        }
    }

    /// Fuses the reading's fix and target.
    fn fuse(&mut self, m: &TipMeasurement) -> Reading {
        if let Some(t) = m.target.filter(finite3) {
            match self.estimate.fuse_target(v3(t)) {
                TargetFix::Fused => {}
                TargetFix::Outlier => self.stats.target_outliers += 1,
                TargetFix::Jumped => self.stats.target_jumps += 1,
            }
        }
        let Some(pose) = m.pose else {
            self.stats.no_fix += 1;
            return Reading::NoFix;
        };
        // A spinning shaft has no bevel direction to measure; only its heading counts.
        let bevel = pose.bevel.filter(|b| finite3(b) && !self.spinning).map(v3);
        let usable = finite3(&pose.position) && finite3(&pose.heading);
        self.estimate.sensor_measures_roll(pose.bevel.is_some());
        if usable && self.estimate.fuse_position(v3(pose.position)) {
            let _ = self.estimate.fuse_orientation(v3(pose.heading), bevel);
            self.last_fix_depth = self.depth;
            Reading::Fused
        } else {
            self.stats.outliers += 1;
            Reading::Outlier
        }
    }

    /// Predicts the rest of the continuation and re-plans it when it misses or is unsafe.
    fn steer(&mut self, seq: u32, reading: Reading) -> SteerReply {
        let remaining = self.remaining();
        let now = self.predict(&remaining);
        // Two standard deviations of the tip's position estimate are kept clear on top of the
        // scenario's floor: the true tip may be that far from where the estimate has it.
        let floor = self.scenario.options.min_clearance;
        let margin = STEER_MARGIN_SDS * self.estimate.margin_sd();
        let too_close = !(now.min_clearance > floor + margin);
        // Half the margin lost and nothing passes the check: the estimate puts the tip within
        // one standard deviation of the floor, so going on risks the obstacle itself.
        let urgent = !(now.min_clearance > floor + 0.5 * margin);
        let mut reply = SteerReply {
            seq,
            command: Command::Continue,
            reading,
            replanned: false,
            predicted_error_mm: now.target_error,
            predicted_clearance_mm: now.min_clearance,
            evaluations: 0,
        };
        // The tracker keeps putting the tip elsewhere: the tip may be anywhere within that
        // offset of the estimate, and a replan on an estimate that has lost the tip is no
        // safer than the path it replaces. Near an obstacle the run stops, reported, before it
        // can touch (in the world at twice the controller's assumption the collisions came
        // here: docs/execution.md, "Twice the world").
        let lost = self.estimate.lost_offset();
        if lost > 0.0 && !(now.min_clearance > floor + margin + lost) {
            reply.command = Command::Stop(StopReason::TrackingLost);
            self.stopped = Some(StopReason::TrackingLost);
            self.last_reply = Some(reply.clone());
            return reply;
        }
        let ahead: f32 = remaining.iter().map(|s| s.op.inserted_mm()).sum();
        let trigger = self.config.replan_error_mm.max(REPLAN_DEFER_PER_MM * ahead);
        // Without insertion since the last replan (a turn, read), a new one only when the
        // clearance has lost half its margin: a continuation planned on the margin's edge is
        // otherwise re-planned after every turn.
        let advanced = self.depth > self.last_replan_depth + DONE_SLACK;
        if (advanced && (now.target_error > trigger || too_close)) || urgent {
            self.last_replan_depth = self.depth;
            let early = self.config.noise.curvature_walk > 0.0
                && self.scenario.arc_duty() < 1.0
                && !(self.early_refused || too_close || urgent)
                && ahead > ONLY_TRIM_WITHIN_MM;
            let input = ReplanInput {
                scenario: &self.scenario,
                tip: self.estimate.tip,
                target: self.estimate.target,
                radius: self.radius(),
                twist_deg: self.base,
                iterations: self.config.iterations,
                margin,
                inserted_mm: self.depth,
                dead_band_deg: self.config.rotation_dead_band_deg,
                arc_duty: self.scenario.arc_duty(),
                spend_reserve: urgent || now.target_error > trigger,
                turn_early: early,
            };
            let (found, evaluations, _) = if ahead > ONLY_TRIM_WITHIN_MM {
                replan(&input, &segments_of(&remaining).unwrap_or_default())
            } else {
                (None, 0, 0)
            };
            reply.evaluations = evaluations;
            self.early_refused = early && found.is_none();
            if self.early_refused {
                self.last_reply = Some(reply.clone());
                return reply;
            }
            let found = found
                .or_else(|| self.trimmed(&remaining, &now, floor + margin))
                .or_else(|| {
                    let better = CLOSER_BY * now.target_error;
                    super::aimed::closest_approach(&input, better, &(evaluations, 0))
                });
            match found {
                Some(r) => {
                    self.stats.replans += 1;
                    reply.replanned = true;
                    reply.predicted_error_mm = r.prediction.target_error;
                    reply.predicted_clearance_mm = r.prediction.min_clearance;
                    self.issue(&r.steps);
                    reply.command = Command::Replace(r.steps);
                }
                None => {
                    self.stats.replan_failures += 1;
                    if urgent {
                        reply.command = Command::Stop(StopReason::NoSafeContinuation);
                        self.stopped = Some(StopReason::NoSafeContinuation);
                    }
                }
            }
        }
        self.last_reply = Some(reply.clone());
        reply
    }

    /// Near the end, where no replan can bend the path any more: the last push lengthened or
    /// shortened so the predicted end comes abreast of the target, if that comes closer and
    /// keeps `kept_clear` (the floor and the margin) from every obstacle.
    fn trimmed(
        &self,
        remaining: &Steps,
        now: &Prediction,
        kept_clear: f32,
    ) -> Option<super::replan::Replanned> {
        let mut steps = remaining.clone();
        let last = steps.last_mut()?;
        let along = (self.estimate.target - now.end.p).dot(&now.end.e3());
        let length = match last.op {
            Op::Rotate { .. } => return None,
            op => op.inserted_mm(),
        };
        *last = resized_step(&self.scenario.driver, last, (length + along).max(0.0)).ok()?;
        let prediction = self.predict(&steps);
        let better = prediction.target_error + 1e-4 < now.target_error;
        (better && prediction.min_clearance > kept_clear).then_some(super::replan::Replanned {
            steps,
            prediction,
            evaluations: 0,
            iterations: 0,
        })
    }
}
