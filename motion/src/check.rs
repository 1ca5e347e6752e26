//! An independent check of a step train against the axes' limits, step by step.
//!
//! It knows nothing of how the train was made: it sees the events, keeps each axis' position
//! and its last interval, and checks every step. Speed: no interval shorter than the top
//! speed's. Acceleration: the speed over an interval is the mean speed, which under constant
//! acceleration is the speed at the interval's middle, so two consecutive intervals `c1`, `c2`
//! (signed by direction) change the speed by at most `A·(c1 + c2)/2`, allowing for the
//! rounding of each interval to whole ticks (one tick on each). A step after a long pause counts
//! from rest. Soft limits: every position within the axis' limits.

use crate::config::{Axis, MotionConfig};
use crate::runner::StepEvent;

/// What a train did wrong, and at which tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Violation {
    /// An interval shorter than the top speed allows.
    Speed {
        /// Which axis.
        axis: Axis,
        /// When (ticks from the start).
        tick: u64,
        /// The speed (steps/s).
        speed: f64,
    },
    /// A change of speed faster than the acceleration allows.
    Accel {
        /// Which axis.
        axis: Axis,
        /// When.
        tick: u64,
        /// The acceleration (steps/s²) over the two intervals.
        accel: f64,
    },
    /// A position past a soft limit.
    SoftLimit {
        /// Which axis.
        axis: Axis,
        /// When.
        tick: u64,
    },
}

/// The checker's state.
#[derive(Clone, Copy, Debug)]
pub struct TrainCheck {
    cfg: MotionConfig,
    tick: u64,
    pos: [i32; 2],
    /// When each axis last stepped or came to rest.
    last_step: [Option<u64>; 2],
    /// The last interval of each axis, signed by its direction (ticks).
    last_interval: [Option<f64>; 2],
    /// Largest acceleration seen, as a share of the limit (rounding allowance excluded).
    pub peak_accel_share: [f64; 2],
    /// Largest speed seen, as a share of the limit.
    pub peak_speed_share: [f64; 2],
}

impl TrainCheck {
    /// A check of a train that starts at rest at `pos` (steps).
    pub fn new(cfg: MotionConfig, pos: [i32; 2]) -> TrainCheck {
        TrainCheck {
            cfg,
            tick: 0,
            pos,
            last_step: [Some(0); 2],
            last_interval: [None; 2],
            peak_accel_share: [0.0; 2],
            peak_speed_share: [0.0; 2],
        }
    }

    /// Positions reached (steps).
    pub fn position(&self) -> [i32; 2] {
        self.pos
    }

    /// Ticks elapsed.
    pub fn ticks(&self) -> u64 {
        self.tick
    }

    /// The train is at rest (stopped between moves): the next step of each axis counts from
    /// rest.
    pub fn at_rest(&mut self) {
        self.last_step = [Some(self.tick); 2];
        self.last_interval = [None; 2];
    }

    /// Checks one event.
    pub fn push(&mut self, e: &StepEvent) -> Result<(), Violation> {
        self.tick += u64::from(e.ticks);
        let f = f64::from(self.cfg.tick_hz);
        for axis in Axis::BOTH {
            let i = axis as usize;
            if !e.step[i] {
                continue;
            }
            let a = &self.cfg.axes[i];
            let top = f64::from(a.max_speed) * f64::from(a.steps_per_unit);
            let acc = f64::from(a.max_accel) * f64::from(a.steps_per_unit);
            self.pos[i] = self.pos[i].saturating_add(i32::from(e.dir[i]));
            let (lo, hi) = self.cfg.limit_steps(axis);
            if !(lo..=hi).contains(&self.pos[i]) {
                return Err(Violation::SoftLimit {
                    axis,
                    tick: self.tick,
                });
            }
            let c = self.last_step[i].map_or(self.tick, |t| self.tick - t) as f64;
            self.last_step[i] = Some(self.tick);
            let speed = f / c;
            self.peak_speed_share[i] = self.peak_speed_share[i].max(speed / top);
            if speed > top {
                return Err(Violation::Speed {
                    axis,
                    tick: self.tick,
                    speed,
                });
            }
            let dir = f64::from(e.dir[i]);
            // From rest: a virtual interval of infinite length before this one.
            let (v1, c1) = match self.last_interval[i] {
                Some(p) => (f / p, libm::fabs(p)),
                None => (0.0, 0.0),
            };
            let v2 = dir * speed;
            let dt = (c1 + c) / (2.0 * f);
            let rounding = |c: f64| if c > 1.0 { f / (c - 1.0) - f / c } else { 0.0 };
            let allowed = acc * dt + rounding(c1) + rounding(c);
            let change = libm::fabs(v2 - v1);
            self.peak_accel_share[i] = self.peak_accel_share[i].max(change / dt / acc);
            if change > allowed {
                return Err(Violation::Accel {
                    axis,
                    tick: self.tick,
                    accel: change / dt,
                });
            }
            self.last_interval[i] = Some(dir * c);
        }
        Ok(())
    }
}
