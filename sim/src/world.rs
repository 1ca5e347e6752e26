//! The world of one simulated insertion: the robot (the driver's insertion and rotation stages),
//! the tissue (the needle's perturbed mechanics) and the tracker, driven one [`Step`] at a time.
//!
//! Mechanics, each piece of it a documented [`Perturbation`] parameter:
//! - an arc (`insert`) is an arc of radius r / (f_run · f_seg), the run's and the segment's
//!   curvature factors (1 + N(0, spread), at least [`MIN_FACTOR`]); a new segment factor is drawn
//!   at the first `insert` after a rotation or a line;
//! - the tip advances the commanded length plus N(0, σ·√(L / 100 mm)) (never negative);
//! - a spun line (`insert_spin`) keeps a residual curvature (imperfect duty cycling): drift rates
//!   d1, d2 ~ N(0, σ) mm/mm across the heading, drawn per line, bend it towards d1 e1 + d2 e2
//!   with curvature 2·|d| / [`DRIFT_REFERENCE_MM`] (a 50 mm line ends |d|·50 mm sideways);
//! - the shaft is a torsional spring with play: the tip roll stays within ± lag·depth of the base
//!   roll and moves only when the base drags it (a backlash). After any rotation larger than the
//!   play the tip rests lag·depth behind the base: its bend plane is off by lag·depth, the "lag
//!   of the tip behind the base rotation" the torsion literature measures. The tip's *turn* is
//!   Δ − 2·lag·depth when it rested on the far side of the play (after a spin, whose alternating
//!   turns leave it lag·depth past the base on the side of its first turn), but its error is
//!   still lag·depth: the play is not counted twice;
//! - the entry point and direction are off by their draws, and the true target is displaced.
//!
//! The tracker measures the tip after every piece of insertion (pieces at most
//! `measure_every_mm` and 1 mm long) and after every rotation (`measure.rs`).
//!
//! The [`WorldEffects`] (layers, a pushed target, the tracker's bias, registration, latency and
//! 5-DOF, imaging's rate and delay) act through hooks: a layered push (`layered.rs`),
//! [`World::moved`] after the tip moves, and the measurement. With every effect off none of
//! them draws or changes a bit.

use crate::drawn::{Drawn, StepDraw};
use crate::effects::layers::Move;
use crate::effects::{Active, EffectsError, WorldEffects};
use crate::executed::executed_part;
use crate::factor::MIN_FACTOR;
use crate::random::{seeded, Draw, SplitMix64};
use crate::reading::Measurement;
use crate::{PerturbError, Perturbation, DRIFT_REFERENCE_MM};
use planner_core::execute::nominal::posture_frame;
use planner_core::execute::perturbation::TorsionPlay;
use planner_core::execute::schedule::{Op, Posture, Schedule, Step, Steps};
use planner_core::model::clearance::closest;
use planner_core::model::kinematics::{rotate, Frame, V3};
use planner_core::model::scenario::Workspace;
use planner_core::{Scenario, SegmentKind};
use std::fmt;
use std::ops::ControlFlow;

/// Offsets the tracker stream from the physics stream of the same seed.
const TRACKER_STREAM: u64 = 0x5452_4143_4B45_5221;

/// How a step ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Executed {
    /// The commanded insertion done (mm; all of it unless the controller broke off).
    pub inserted_mm: f32,
    /// The controller broke off the step.
    pub interrupted: bool,
}

#[derive(Clone, Copy, PartialEq)]
enum Last {
    Nothing,
    Rotate,
    Insert,
    Spin,
    Duty,
}

/// One simulated insertion in progress.
pub struct World {
    scenario: Scenario,
    pub(crate) p: Perturbation,
    physics: SplitMix64,
    pub(crate) tracker: SplitMix64,
    pub(crate) tip: Frame,
    start: Frame,
    segment_factor: f32,
    line_drift: [f32; 2],
    last: Last,
    pub(crate) torsion: TorsionPlay,
    pub(crate) depth: f32,
    pub(crate) commanded: f32,
    pub(crate) true_target: V3,
    points: Vec<[f32; 3]>,
    min_clearance: f32,
    drawn: Drawn,
    executed: Vec<Step>,
    pub(crate) fx: Active,
    pub(crate) moves: Vec<Move>,
}

pub(crate) fn normal(g: &mut SplitMix64, sd: f32) -> f32 {
    g.normal(f64::from(sd)) as f32
}

pub(crate) fn v3(a: [f32; 3]) -> V3 {
    V3::new(a[0], a[1], a[2])
}

/// The frame turned rigidly by `angle` (radians) about the unit `axis`.
pub(crate) fn turned(f: &Frame, axis: V3, angle: f32) -> Frame {
    let mut out = *f;
    for i in 0..3 {
        out.r
            .set_column(i, &rotate(f.r.column(i).into(), axis, angle));
    }
    out
}

impl World {
    /// The world of a run: the needle set at `posture` (with the entry errors drawn), the target
    /// displaced; `seed` fixes every draw of the run.
    pub fn new(
        scenario: &Scenario,
        posture: &Posture,
        p: &Perturbation,
        seed: u64,
    ) -> Result<World, PerturbError> {
        p.validate()?;
        let mut physics = seeded(seed);
        let curvature_factor = (1.0 + normal(&mut physics, p.curvature_spread)).max(MIN_FACTOR);
        let mut draw3 = |sd| [0; 3].map(|_| normal(&mut physics, sd));
        let entry_offset_mm = draw3(p.entry_position_mm);
        let tilt = draw3(p.entry_direction_deg);
        let target_shift_mm = draw3(p.target_shift_mm);
        let entry_tilt_deg = [tilt[0], tilt[1]];
        let at = Schedule {
            posture: *posture,
            steps: Steps::new(),
            duration_s: 0.0,
            max_twist_deg: 0.0,
        };
        let mut tip = posture_frame(scenario, &at);
        tip.p += v3(entry_offset_mm);
        if entry_tilt_deg != [0.0; 2] {
            tip = turned(&tip, tip.e1(), entry_tilt_deg[0].to_radians());
            tip = turned(&tip, tip.e2(), entry_tilt_deg[1].to_radians());
        }
        let mut world = World {
            scenario: scenario.clone(),
            p: *p,
            physics,
            tracker: seeded(seed ^ TRACKER_STREAM),
            tip,
            start: tip,
            segment_factor: 1.0,
            line_drift: [0.0; 2],
            last: Last::Nothing,
            torsion: TorsionPlay::new(p),
            depth: 0.0,
            commanded: 0.0,
            true_target: v3(scenario.target.position) + v3(target_shift_mm),
            points: Vec::new(),
            min_clearance: f32::INFINITY,
            drawn: Drawn {
                curvature_factor,
                entry_offset_mm,
                entry_tilt_deg,
                target_shift_mm,
                steps: Vec::new(),
                effects: None,
            },
            executed: Vec::new(),
            fx: Active::off(v3(scenario.target.position) + v3(target_shift_mm)),
            moves: Vec::new(),
        };
        world.record(tip.p);
        Ok(world)
    }

    /// The world of a run executing `schedule` with the `effects` on top of `p` (each effect
    /// draws from its own stream: with every effect off this is [`World::new`], bit for bit).
    pub fn with_effects(
        scenario: &Scenario,
        schedule: &Schedule,
        p: &Perturbation,
        effects: &WorldEffects,
        seed: u64,
    ) -> Result<World, WorldError> {
        effects.validate().map_err(WorldError::Effects)?;
        let mut world =
            World::new(scenario, &schedule.posture, p, seed).map_err(WorldError::Perturbation)?;
        if !effects.is_off() {
            let rest = world.true_target;
            world.fx = Active::new(effects, scenario, schedule, &world.tip, rest, seed);
            world.drawn.effects = Some(world.fx.drawn());
        }
        Ok(world)
    }

    /// The tip moved or turned: the effects follow it (the target is pushed, the histories
    /// of latency and imaging recorded). Nothing without effects.
    pub(crate) fn moved(&mut self) {
        if self.fx.any() {
            let (c, base) = (self.commanded, self.torsion.base_deg);
            self.true_target = self.fx.moved(c, base, &self.tip, self.true_target);
        }
    }

    /// Insertion the tip has truly made along its path (mm); the commanded insertion is the
    /// measurements' `depth_mm`.
    pub fn tip_depth(&self) -> f32 {
        self.depth
    }

    /// The true tip frame.
    pub fn tip(&self) -> Frame {
        self.tip
    }

    /// The true (displaced) target.
    pub fn true_target(&self) -> V3 {
        self.true_target
    }

    /// The true tip frame at the entry, before any insertion.
    pub fn start(&self) -> &Frame {
        &self.start
    }

    /// The scenario the world executes.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The true tip path so far, points at most 1 mm apart from the entry.
    pub fn points(&self) -> &[[f32; 3]] {
        &self.points
    }

    /// Smallest clearance of the true path to any obstacle surface so far (mm; negative inside
    /// one; infinite without obstacles). Plane scenarios' circles are cylinders across the plane.
    pub fn min_clearance(&self) -> f32 {
        self.min_clearance
    }

    /// What was drawn so far.
    pub fn drawn(&self) -> &Drawn {
        &self.drawn
    }

    /// The steps executed so far (one broken off with the length it reached, and the time and
    /// turns that took).
    pub fn executed(&self) -> &[Step] {
        &self.executed
    }

    /// The perturbation the world runs with.
    pub fn perturbation(&self) -> &Perturbation {
        &self.p
    }

    /// Executes one driver step; `on_measure` sees every measurement taken during it and may
    /// break the step off (the tip stays where the measurement saw it).
    pub fn execute(
        &mut self,
        step: &Step,
        mut on_measure: impl FnMut(&Measurement) -> ControlFlow<()>,
    ) -> Executed {
        self.execute_seen(step, |m, _, _| on_measure(m))
    }

    /// [`World::execute`], `on_measure` also seeing the true tip frame and the true target at
    /// each measurement (what the tracker's reading should have been; the world's own draws are
    /// the same).
    pub fn execute_seen(
        &mut self,
        step: &Step,
        mut on_measure: impl FnMut(&Measurement, &Frame, V3) -> ControlFlow<()>,
    ) -> Executed {
        let mut draw = StepDraw::default();
        let done = match step.op {
            Op::Rotate { angle_deg } => {
                draw.tip_rotation_deg = self.rotate_base(angle_deg);
                self.last = Last::Rotate;
                self.moved();
                let m = self.measure();
                let _ = on_measure(&m, &self.tip, self.true_target);
                Executed {
                    inserted_mm: 0.0,
                    interrupted: false,
                }
            }
            Op::Insert { length_mm } => {
                if self.last != Last::Insert {
                    let f = 1.0 + normal(&mut self.physics, self.p.segment_curvature_spread);
                    self.segment_factor = f;
                }
                self.last = Last::Insert;
                draw.segment_factor = self.segment_factor;
                let factor = (self.drawn.curvature_factor * self.segment_factor).max(MIN_FACTOR);
                let radius = self.scenario.needle.curvature_radius / factor;
                self.push(
                    SegmentKind::Arc,
                    length_mm,
                    radius,
                    &mut draw,
                    &mut on_measure,
                )
            }
            Op::InsertSpin { length_mm, .. } => {
                if self.last != Last::Spin {
                    let sd = self.p.line_drift_mm_per_mm;
                    self.line_drift = [0; 2].map(|_| normal(&mut self.physics, sd));
                }
                self.last = Last::Spin;
                draw.drift = self.line_drift;
                let [d1, d2] = self.line_drift;
                let size = libm::sqrtf(d1 * d1 + d2 * d2);
                let done = if size == 0.0 {
                    let radius = self.scenario.needle.curvature_radius;
                    self.push(
                        SegmentKind::Line,
                        length_mm,
                        radius,
                        &mut draw,
                        &mut on_measure,
                    )
                } else {
                    // The residual curvature bends the line towards d1 e1 + d2 e2: roll e2 there,
                    // push an arc, roll back (the bevel itself is spinning, not turned).
                    let roll = libm::atan2f(-d1, d2);
                    self.tip = self.tip.rolled(roll);
                    let radius = DRIFT_REFERENCE_MM / (2.0 * size);
                    let done = self.push(
                        SegmentKind::Arc,
                        length_mm,
                        radius,
                        &mut draw,
                        &mut on_measure,
                    );
                    self.tip = self.tip.rolled(-roll);
                    done
                };
                draw.tip_rotation_deg = self.spin_settles();
                done
            }
            Op::InsertDuty { length_mm, duty } => {
                self.duty_cycled(length_mm, duty, &mut draw, &mut on_measure)
            }
        };
        self.moved();
        if let Some(d) = self.drawn.effects.as_mut() {
            // The layers' and the push's state as the step left it.
            *d = self.fx.drawn();
        }
        self.drawn.steps.push(draw);
        self.executed.push(executed_part(step, done.inserted_mm));
        done
    }

    /// A duty-cycled push: the held share bends the needle by `duty` of its (perturbed)
    /// curvature towards the bevel, the spun share drifts as a spun line does; both draws are
    /// fresh after any other step. One arc carries the sum of the two curvatures.
    fn duty_cycled(
        &mut self,
        length_mm: f32,
        duty: f32,
        draw: &mut StepDraw,
        on_measure: &mut impl FnMut(&Measurement, &Frame, V3) -> ControlFlow<()>,
    ) -> Executed {
        if self.last != Last::Duty {
            self.segment_factor = 1.0 + normal(&mut self.physics, self.p.segment_curvature_spread);
            let sd = self.p.line_drift_mm_per_mm;
            self.line_drift = [0; 2].map(|_| normal(&mut self.physics, sd));
        }
        self.last = Last::Duty;
        draw.segment_factor = self.segment_factor;
        draw.drift = self.line_drift;
        let factor = (self.drawn.curvature_factor * self.segment_factor).max(MIN_FACTOR);
        let bend = duty.clamp(0.0, 1.0) * factor / self.scenario.needle.curvature_radius;
        let [d1, d2] = self.line_drift;
        let across = [
            2.0 * d1 / DRIFT_REFERENCE_MM,
            bend + 2.0 * d2 / DRIFT_REFERENCE_MM,
        ];
        let size = libm::sqrtf(across[0] * across[0] + across[1] * across[1]);
        let done = if size == 0.0 {
            let radius = self.scenario.needle.curvature_radius;
            self.push(SegmentKind::Line, length_mm, radius, draw, on_measure)
        } else {
            let roll = libm::atan2f(-across[0], across[1]);
            self.tip = self.tip.rolled(roll);
            let done = self.push(SegmentKind::Arc, length_mm, 1.0 / size, draw, on_measure);
            self.tip = self.tip.rolled(-roll);
            done
        };
        draw.tip_rotation_deg = self.spin_settles();
        done
    }

    /// Turns the base by `angle_deg`; the tip follows through the play. Returns the tip's turn.
    fn rotate_base(&mut self, angle_deg: f32) -> f32 {
        let turn = self.torsion.rotate(angle_deg, self.depth);
        if turn != 0.0 {
            self.tip = self.tip.rolled(turn.to_radians());
        }
        turn
    }

    /// After a spin the tip rests past the base by the play ([`TorsionPlay::spin_settles`]).
    /// Returns the tip's net turn.
    fn spin_settles(&mut self) -> f32 {
        let turn = self.torsion.spin_settles(self.depth);
        if self.torsion.lag_per_mm * self.depth != 0.0 {
            self.tip = self.tip.rolled(turn.to_radians());
        }
        turn
    }

    /// Pushes the needle `length` (commanded) along a segment of `kind`, in pieces.
    fn push(
        &mut self,
        kind: SegmentKind,
        length: f32,
        radius: f32,
        draw: &mut StepDraw,
        on_measure: &mut impl FnMut(&Measurement, &Frame, V3) -> ControlFlow<()>,
    ) -> Executed {
        let sd = self.p.insertion_error_mm * libm::sqrtf(length.max(0.0) / 100.0);
        let error = normal(&mut self.physics, sd);
        let true_len = (length + error).max(0.0);
        draw.length_error_mm = true_len - length;
        if self.fx.layers.is_some() {
            return self.push_layered(kind, length, true_len, radius, on_measure);
        }
        let start = self.tip;
        let mut t_prev = 0.0;
        self.in_pieces(length, true_len, on_measure, |w, share| {
            let t = true_len * share;
            w.clearance_along(
                &start.advanced(kind, t_prev, radius),
                kind,
                t - t_prev,
                radius,
            );
            w.tip = start.advanced(kind, t, radius);
            w.record(w.tip.p);
            w.depth += t - t_prev;
            t_prev = t;
        })
    }

    pub(crate) fn record(&mut self, p: V3) {
        self.points.push([p.x, p.y, p.z]);
        if self.scenario.options.workspace == Workspace::PlaneYz {
            // Circles of the plane are cylinders across it: clearance in the y-z projection.
            for ob in &self.scenario.obstacles {
                let (dy, dz) = (p.y - ob.center[1], p.z - ob.center[2]);
                let d = libm::sqrtf(dy * dy + dz * dz) - ob.radius;
                self.min_clearance = self.min_clearance.min(d);
            }
        }
    }

    /// Exact clearance of one piece (3-D scenarios; the plane's are measured at the points).
    pub(crate) fn clearance_along(
        &mut self,
        start: &Frame,
        kind: SegmentKind,
        len: f32,
        radius: f32,
    ) {
        if self.scenario.options.workspace != Workspace::Space {
            return;
        }
        for ob in &self.scenario.obstacles {
            let d = closest(start, kind, len, radius, &v3(ob.center)).distance - ob.radius;
            self.min_clearance = self.min_clearance.min(d);
        }
    }
}

/// Why a world cannot be made.
#[derive(Clone, Debug, PartialEq)]
pub enum WorldError {
    /// The perturbation is invalid.
    Perturbation(PerturbError),
    /// A world effect is invalid.
    Effects(EffectsError),
}

impl fmt::Display for WorldError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WorldError::Perturbation(e) => write!(f, "{e}"),
            WorldError::Effects(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for WorldError {}
