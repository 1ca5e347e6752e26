//! The effects of one run as the world applies them: what was drawn (each effect from its own
//! stream), and the hooks the world calls after the tip moves and when the tracker measures.

use super::bias::{BiasField, Registration};
use super::delay::{Imaging, Latency};
use super::layers::Layers;
use super::push::TargetPush;
use super::{WorldEffects, DEFAULT_INSERTION_SPEED_MM_S};
use crate::random::seeded;
use planner_core::execute::schedule::{Op, Schedule};
use planner_core::model::kinematics::{Frame, V3};
use planner_core::Scenario;
use serde::Serialize;

/// Offsets of each effect's stream from the physics stream of the same seed: turning one
/// effect on changes neither the tissue's, the tracker's nor another effect's draws.
const BIAS_STREAM: u64 = 0x4249_4153_4649_454C;
const REGISTRATION_STREAM: u64 = 0x5245_4749_5354_4552;
const LAYER_STREAM: u64 = 0x4C41_5945_5253_2121;
const PUSH_STREAM: u64 = 0x5055_5348_5441_5247;

/// What the world's effects drew for one run (`drawn.effects` with `--detail`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct EffectsDrawn {
    /// The field-distortion bias.
    pub bias: Option<BiasField>,
    /// The registration error.
    pub registration: Option<Registration>,
    /// The layers (boundaries, factors, stalls).
    pub layers: Option<Layers>,
    /// The target's push.
    pub push: Option<TargetPush>,
    /// Tracker latency as insertion (mm).
    pub latency_mm: Option<f32>,
}

/// The effects of one run in progress.
#[derive(Clone, Debug)]
pub(crate) struct Active {
    pub roll_seen: bool,
    pub bias: Option<BiasField>,
    pub registration: Option<Registration>,
    pub layers: Option<Layers>,
    pub push: Option<TargetPush>,
    pub latency: Option<Latency>,
    pub imaging: Option<Imaging>,
    latency_mm: Option<f32>,
    rest_target: V3,
}

/// Inserted length over insertion time of the schedule's plain pushes, if it has any.
fn schedule_speed(schedule: &Schedule) -> Option<f32> {
    let (mut mm, mut s) = (0.0f32, 0.0f32);
    for step in schedule.steps.iter() {
        if let Op::Insert { length_mm } = step.op {
            mm += length_mm;
            s += step.duration_s;
        }
    }
    (mm > 0.0 && s > 0.0).then(|| mm / s)
}

/// The planned insertion's length (mm).
fn planned_length(schedule: &Schedule) -> f32 {
    schedule
        .steps
        .iter()
        .map(|s| match s.op {
            Op::Insert { length_mm }
            | Op::InsertSpin { length_mm, .. }
            | Op::InsertDuty { length_mm, .. } => length_mm,
            Op::Rotate { .. } => 0.0,
        })
        .sum()
}

impl Active {
    /// No effect: today's world.
    pub fn off(rest_target: V3) -> Active {
        Active {
            roll_seen: true,
            bias: None,
            registration: None,
            layers: None,
            push: None,
            latency: None,
            imaging: None,
            latency_mm: None,
            rest_target,
        }
    }

    /// The effects of the run of `seed` executing `schedule`, the tip starting at `tip` and
    /// the target resting at `rest_target`.
    pub fn new(
        e: &WorldEffects,
        scenario: &Scenario,
        schedule: &Schedule,
        tip: &Frame,
        rest_target: V3,
        seed: u64,
    ) -> Active {
        let mut a = Active::off(rest_target);
        a.roll_seen = e.tracker_dof >= 6;
        if e.tracker_bias_mm > 0.0 {
            let g = &mut seeded(seed ^ BIAS_STREAM);
            a.bias = Some(BiasField::draw(g, e.tracker_bias_mm));
        }
        if e.registration_error_mm > 0.0 {
            let entry = scenario.entry.position;
            let target = scenario.target.position;
            let centre = V3::from_fn(|i, _| 0.5 * (entry[i] + target[i]));
            let g = &mut seeded(seed ^ REGISTRATION_STREAM);
            a.registration = Some(Registration::draw(g, e.registration_error_mm, centre));
        }
        if e.layers > 0 {
            let g = &mut seeded(seed ^ LAYER_STREAM);
            let length = planned_length(schedule);
            let spread = e.layer_curvature_spread;
            a.layers = Some(Layers::draw(g, e.layers, length, spread, e.puncture_mm));
        }
        if e.target_push_mm > 0.0 {
            let g = &mut seeded(seed ^ PUSH_STREAM);
            a.push = Some(TargetPush::draw(g, e.target_push_mm));
        }
        let speed = if e.insertion_speed_mm_s > 0.0 {
            e.insertion_speed_mm_s
        } else {
            schedule_speed(schedule).unwrap_or(DEFAULT_INSERTION_SPEED_MM_S)
        };
        if e.tracker_latency_ms > 0.0 {
            let lag = e.tracker_latency_ms / 1000.0 * speed;
            a.latency_mm = Some(lag);
            a.latency = Some(Latency::new(lag, *tip));
        }
        if e.target_imaging_hz > 0.0 || e.target_imaging_delay_ms > 0.0 {
            let delay = e.target_imaging_delay_ms / 1000.0;
            let hz = e.target_imaging_hz;
            a.imaging = Some(Imaging::new(hz, delay, speed, rest_target));
        }
        a
    }

    /// What was drawn.
    pub fn drawn(&self) -> EffectsDrawn {
        EffectsDrawn {
            bias: self.bias.clone(),
            registration: self.registration,
            layers: self.layers.clone(),
            push: self.push.clone(),
            latency_mm: self.latency_mm,
        }
    }

    /// Whether any effect draws or records (with none, the world is today's).
    pub fn any(&self) -> bool {
        !self.roll_seen
            || self.bias.is_some()
            || self.registration.is_some()
            || self.layers.is_some()
            || self.push.is_some()
            || self.latency.is_some()
            || self.imaging.is_some()
    }

    /// The tip moved or turned to `tip` with `commanded` mm inserted: the target is pushed,
    /// the histories recorded. Returns the true target.
    pub fn moved(&mut self, commanded: f32, tip: &Frame, target: V3) -> V3 {
        let target = match self.push.as_mut() {
            Some(p) => self.rest_target + p.displacement(tip, self.rest_target),
            None => target,
        };
        if let Some(l) = self.latency.as_mut() {
            l.record(commanded, *tip);
        }
        if let Some(i) = self.imaging.as_mut() {
            i.record(commanded, target);
        }
        target
    }

    /// The tip the tracker reports on with `commanded` mm inserted (before its noise).
    pub fn tip_seen(&self, commanded: f32, tip: &Frame) -> Frame {
        match &self.latency {
            Some(l) => l.seen(commanded, tip),
            None => *tip,
        }
    }

    /// A measured tip frame (its noise drawn) as the tracker's frame has it: biased by the
    /// field, moved by the registration error.
    pub fn distorted(&self, mut f: Frame) -> Frame {
        if let Some(b) = &self.bias {
            f.p += b.at(f.p);
        }
        match &self.registration {
            Some(r) => r.frame(&f),
            None => f,
        }
    }

    /// The target a reading carries with `commanded` mm inserted (`None` between images).
    pub fn target_seen(&mut self, commanded: f32, target: V3) -> Option<V3> {
        match self.imaging.as_mut() {
            Some(i) => i.seen(commanded),
            None => Some(target),
        }
    }
}
