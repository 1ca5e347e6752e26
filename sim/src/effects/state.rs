//! The effects of one run as the world applies them: what was drawn (each effect from its own
//! stream), and the hooks the world calls after the tip moves and when the tracker measures.

use super::bias::{BiasField, Registration};
use super::delay::{Imaging, Latency};
use super::layers::Layers;
use super::push::TargetPush;
use super::{WorldEffects, DEFAULT_INSERTION_SPEED_MM_S, DEFAULT_ROTATION_SPEED_DEG_S};
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
    clock: Clock,
}

/// The world's clock: the robot's time, insertion at the insertion speed and rotations at the
/// driver's rotation speed (the base's turns; a spin's whole turns are in its push's time).
#[derive(Clone, Copy, Debug)]
struct Clock {
    insert_speed: f32,
    rotate_speed: f32,
    commanded: f32,
    base_deg: f32,
    t: f32,
}

impl Clock {
    /// The time when `commanded` mm are inserted and the base is at `base_deg` (s).
    fn at(&mut self, commanded: f32, base_deg: f32) -> f32 {
        let pushed = (commanded - self.commanded).max(0.0) / self.insert_speed;
        let turned = (base_deg - self.base_deg).abs() / self.rotate_speed;
        self.t += pushed + turned;
        self.commanded = commanded;
        self.base_deg = base_deg;
        self.t
    }
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
        let clock = Clock {
            insert_speed: DEFAULT_INSERTION_SPEED_MM_S,
            rotate_speed: DEFAULT_ROTATION_SPEED_DEG_S,
            commanded: 0.0,
            base_deg: 0.0,
            t: 0.0,
        };
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
            clock,
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
            let given = e.layer_depths_mm.as_ref().map(|d| d.as_slice());
            let spreads = (e.layer_curvature_spread, e.puncture_mm);
            a.layers = Some(Layers::draw(g, e.layers, given, length, spreads));
        }
        if e.target_push_mm > 0.0 {
            let g = &mut seeded(seed ^ PUSH_STREAM);
            a.push = Some(TargetPush::draw(g, e.target_push_mm));
        }
        let driver = &scenario.driver;
        let speed = if e.insertion_speed_mm_s > 0.0 {
            e.insertion_speed_mm_s
        } else {
            Some(driver.insert_speed)
                .filter(|s| s.is_finite() && *s > 0.0)
                .unwrap_or(DEFAULT_INSERTION_SPEED_MM_S)
        };
        a.clock.insert_speed = speed;
        if driver.rotate_speed.is_finite() && driver.rotate_speed > 0.0 {
            a.clock.rotate_speed = driver.rotate_speed;
        }
        if e.tracker_latency_ms > 0.0 {
            let lag = e.tracker_latency_ms / 1000.0;
            a.latency_mm = Some(lag * speed);
            a.latency = Some(Latency::new(lag, *tip));
        }
        if e.target_imaging_hz > 0.0 || e.target_imaging_delay_ms > 0.0 {
            let delay = e.target_imaging_delay_ms / 1000.0;
            let hz = e.target_imaging_hz;
            a.imaging = Some(Imaging::new(hz, delay, rest_target));
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

    /// The tip moved or turned to `tip` with `commanded` mm inserted and the base at
    /// `base_deg`: the clock runs on, the target is pushed, the histories recorded. Returns the
    /// true target.
    pub fn moved(&mut self, commanded: f32, base_deg: f32, tip: &Frame, target: V3) -> V3 {
        let t = self.clock.at(commanded, base_deg);
        let target = match self.push.as_mut() {
            Some(p) => self.rest_target + p.displacement(tip, self.rest_target),
            None => target,
        };
        if let Some(l) = self.latency.as_mut() {
            l.record(t, *tip);
        }
        if let Some(i) = self.imaging.as_mut() {
            i.record(t, target);
        }
        target
    }

    /// The tip the tracker reports on now (before its noise).
    pub fn tip_seen(&self, tip: &Frame) -> Frame {
        match &self.latency {
            Some(l) => l.seen(self.clock.t, tip),
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

    /// The target a reading carries now (`None` between images).
    pub fn target_seen(&mut self, target: V3) -> Option<V3> {
        match self.imaging.as_mut() {
            Some(i) => i.seen(self.clock.t),
            None => Some(target),
        }
    }
}
