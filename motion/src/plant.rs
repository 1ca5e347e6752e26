//! Simulated axes: the stage behind each motor, for the QEMU board, hil-sim and the tests.
//!
//! Each stage has inertia: the motor pulls it towards the position its pulses command with the
//! torque of a stepper, which grows as the sine of the lag to its peak at one full step behind
//! (the acceleration that torque gives the stage's inertia) and is gone at the pull-out speed;
//! the stage is damped relative to the commanded motion. When the lag passes two full steps the
//! rotor falls a pole behind and the pulses beyond are lost: missed steps, as when a profile
//! asks more speed or acceleration than the stage can follow. The insertion stage closes its home switch at the retracted end (0) and
//! a limit switch at the far end; an optional encoder reads each stage to its resolution.

// The stage's physics, not the planner's: it runs on the host and in QEMU, never on a board that
// drives motors, so libm's f64 sine is fine here and fmath (planner-core) is not a dependency.
#![allow(clippy::disallowed_methods)]

use crate::config::Axis;
use crate::runner::StepEvent;
use crate::safety::Inputs;

/// One simulated axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantAxis {
    /// Speed at which the motor's torque is gone (steps/s).
    pub pull_out: f32,
    /// The acceleration the motor's torque gives the stage's inertia (steps/s²).
    pub torque_accel: f32,
    /// Microsteps of one full step (the lag of peak torque; two of them slip).
    pub full_step: f32,
    /// Motor steps per encoder count (`None`: no encoder).
    pub encoder_steps: Option<u32>,
}

/// The simulated driver: two axes and the insertion stage's switches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantConfig {
    /// Insertion and rotation.
    pub axes: [PlantAxis; 2],
    /// Timer ticks per second (the controller's).
    pub tick_hz: u32,
    /// Where the stages start (steps; the home switch closes at insertion 0 and below).
    pub start: [i32; 2],
    /// Where the far limit switch closes (insertion steps).
    pub end: i32,
}

/// Damping of a stage relative to the commanded motion (share of critical).
const ZETA: f64 = 0.7;

/// Longest integration step (s): a small fraction of the stage's period.
const H: f64 = 20e-6;

/// The simulated driver's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plant {
    cfg: PlantConfig,
    tick: u64,
    /// Where each stage is (steps) and how fast it moves (steps/s).
    x: [f64; 2],
    v: [f64; 2],
    /// Where the motor's pulses put the rotor's field (steps): the commanded position less the
    /// steps slipped.
    field: [f64; 2],
    /// The field's speed over its last pulse (steps/s), the tick of that pulse and its interval.
    field_v: [f64; 2],
    last_pulse: [u64; 2],
    last_interval: [u64; 2],
    missed: [u32; 2],
    /// The e-stop input as wired (pressed or not).
    pub estop: bool,
}

impl Plant {
    /// A plant at `cfg.start`, at rest.
    pub fn new(cfg: PlantConfig) -> Plant {
        let start = cfg.start.map(f64::from);
        Plant {
            cfg,
            tick: 0,
            x: start,
            v: [0.0; 2],
            field: start,
            field_v: [0.0; 2],
            last_pulse: [0; 2],
            last_interval: [0; 2],
            missed: [0; 2],
            estop: false,
        }
    }

    /// Where the stages are (steps, to the nearest).
    pub fn actual(&self) -> [i32; 2] {
        self.x.map(|x| libm::round(x) as i32)
    }

    /// Steps each motor slipped.
    pub fn missed(&self) -> [u32; 2] {
        self.missed
    }

    /// The time (timer ticks since the start).
    pub fn ticks(&self) -> u64 {
        self.tick
    }

    /// The time (ms, wrapping).
    pub fn now_ms(&self) -> u32 {
        (self.tick * 1000 / u64::from(self.cfg.tick_hz.max(1))) as u32
    }

    /// Time passes without a pulse.
    pub fn wait_ms(&mut self, ms: u32) {
        let ticks = u64::from(ms) * u64::from(self.cfg.tick_hz) / 1000;
        self.advance(ticks);
    }

    /// The inputs as the board reads them now.
    pub fn inputs(&self) -> Inputs {
        let at = self.actual();
        let enc = |i: usize| {
            self.cfg.axes[i].encoder_steps.map(|s| {
                let s = s.clamp(1, 1 << 16) as i32;
                at[i].div_euclid(s) * s
            })
        };
        Inputs {
            estop: self.estop,
            limit: at[0] >= self.cfg.end,
            home: at[0] <= 0,
            encoder: [enc(0), enc(1)],
        }
    }

    /// The event's wait, then its pulses.
    pub fn apply(&mut self, e: &StepEvent) {
        self.advance(u64::from(e.ticks));
        for axis in Axis::BOTH {
            let i = axis as usize;
            if e.step[i] {
                self.field[i] += f64::from(e.dir[i]);
                let c = (self.tick - self.last_pulse[i]).max(1);
                self.field_v[i] = f64::from(e.dir[i]) * f64::from(self.cfg.tick_hz) / c as f64;
                self.last_pulse[i] = self.tick;
                self.last_interval[i] = c;
            }
        }
    }

    /// The stages chase their fields for `ticks`.
    fn advance(&mut self, ticks: u64) {
        self.tick += ticks;
        for i in 0..2 {
            // No pulse for two intervals: the field stands.
            if self.tick - self.last_pulse[i] > 2 * self.last_interval[i] {
                self.field_v[i] = 0.0;
            }
        }
        let mut left = ticks as f64 / f64::from(self.cfg.tick_hz.max(1));
        for i in 0..2 {
            self.slip(i);
        }
        while left > 0.0 {
            let settled =
                |i: usize| libm::fabs(self.field[i] - self.x[i]) < 1e-9 && self.v[i] == 0.0;
            if settled(0) && settled(1) {
                return;
            }
            let h = left.min(H);
            for i in 0..2 {
                self.integrate(i, h);
            }
            left -= h;
        }
    }

    fn integrate(&mut self, i: usize, h: f64) {
        let a = &self.cfg.axes[i];
        let (peak, full) = (f64::from(a.torque_accel), f64::from(a.full_step).max(1.0));
        let lag = self.field[i] - self.x[i];
        let half_pi = core::f64::consts::FRAC_PI_2;
        // Stiffness about the field: the torque law's slope at zero lag.
        let omega = libm::sqrt(peak * half_pi / full);
        let pull = peak * libm::sin(half_pi * lag / full);
        let want = pull + 2.0 * ZETA * omega * (self.field_v[i] - self.v[i]);
        let most = if libm::fabs(self.v[i]) < f64::from(a.pull_out) || want * self.v[i] < 0.0 {
            peak
        } else {
            0.0
        };
        self.v[i] += want.clamp(-most, most) * h;
        self.x[i] += self.v[i] * h;
        if libm::fabs(lag) < 1e-6 && libm::fabs(self.v[i]) < 1e-3 && self.field_v[i] == 0.0 {
            self.x[i] = self.field[i];
            self.v[i] = 0.0;
        }
        self.slip(i);
    }

    /// A lag past the slip band loses the pulses beyond it.
    fn slip(&mut self, i: usize) {
        let band = 2.0 * f64::from(self.cfg.axes[i].full_step);
        let lag = self.field[i] - self.x[i];
        if libm::fabs(lag) > band {
            let excess = libm::ceil(libm::fabs(lag) - band);
            self.field[i] -= libm::copysign(excess, lag);
            self.missed[i] = self.missed[i].saturating_add(excess as u32);
        }
    }
}
