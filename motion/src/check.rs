//! An independent check of a step train against the axes' limits, step by step.
//!
//! It knows nothing of how the train was made: it sees the events, keeps each axis' position
//! and its last interval, and checks every step. Speed: no interval shorter than the top
//! speed's. Acceleration: the speed over an interval is the mean speed, which under constant
//! acceleration is the speed at the interval's middle, so two consecutive intervals `c1`, `c2`
//! (signed by direction) may change the speed by at most `A·(c1 + c2)/2`. Intervals are whole
//! ticks, so the check asks that the train be within one tick per interval of a train that keeps
//! this exactly: the intervals moved by a tick each towards less change must keep it. The first
//! step counts from rest (a virtual interval of no length and no speed before it). Soft limits:
//! every position within the axis' limits.

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
        /// The acceleration (steps/s²) over the two intervals, eased by a tick each.
        accel: f64,
        /// The two intervals (ticks, signed by direction; 0 for rest).
        intervals: [f64; 2],
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
    /// Largest acceleration between the mean speeds of consecutive windows of at least
    /// [`WINDOW_S`] in one direction, as a share of the limit, with the windows' ends moved by a
    /// tick each towards less change (any motion whose acceleration stays within the limit
    /// keeps the mean speeds of adjacent windows within it: this is what the stage's inertia
    /// feels, the ticks' rounding all but averaged out).
    pub peak_window_accel_share: [f64; 2],
    windows: [Window; 2],
}

/// Least length of a window of [`TrainCheck::peak_window_accel_share`] (s).
pub const WINDOW_S: f64 = 0.02;

/// The window being counted and the last one finished.
#[derive(Clone, Copy, Debug, Default)]
struct Window {
    start: u64,
    steps: u32,
    dir: i8,
    /// Steps (signed) and length (ticks) of the last window.
    last: Option<(f64, f64)>,
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
            peak_window_accel_share: [0.0; 2],
            windows: [Window::default(); 2],
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
        self.windows = [Window::default(); 2];
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
            let (share, change) = accel_share(self.last_interval[i], dir * c, f, acc);
            self.peak_accel_share[i] = self.peak_accel_share[i].max(share);
            if change > acc {
                return Err(Violation::Accel {
                    axis,
                    tick: self.tick,
                    accel: change,
                    intervals: [self.last_interval[i].unwrap_or(0.0), dir * c],
                });
            }
            self.last_interval[i] = Some(dir * c);
            let share = self.windows[i].step(self.tick, e.dir[i], f) / acc;
            self.peak_window_accel_share[i] = self.peak_window_accel_share[i].max(share);
        }
        Ok(())
    }
}

/// Between the signed intervals `before` (`None`: from rest) and `now` (ticks at `f` Hz): the
/// acceleration as a share of `acc` (the intervals as they are), and the least acceleration
/// of the intervals moved by one tick each towards less change (steps/s²).
fn accel_share(before: Option<f64>, now: f64, f: f64, acc: f64) -> (f64, f64) {
    let c2 = libm::fabs(now);
    let v2 = f / now;
    let Some(p) = before else {
        // From rest: the mean speed of the first interval is reached over half of it.
        let share = libm::fabs(v2) / (c2 / (2.0 * f)) / acc;
        let eased = f / (c2 + 1.0) / ((c2 + 1.0) / (2.0 * f));
        return (share, eased);
    };
    let c1 = libm::fabs(p);
    let v1 = f / p;
    let share = libm::fabs(v2 - v1) / ((c1 + c2) / (2.0 * f)) / acc;
    // Towards less change: the two intervals a tick each towards each other (no further than
    // equal); a reversal's both a tick longer.
    let (e1, e2) = if p * now > 0.0 {
        let m = ((c1 - c2) / 2.0).clamp(-1.0, 1.0);
        (c1 - m, c2 + m)
    } else {
        (c1 + 1.0, c2 + 1.0)
    };
    let (u1, u2) = (libm::copysign(f / e1, p), libm::copysign(f / e2, now));
    let eased = libm::fabs(u2 - u1) / ((e1 + e2) / (2.0 * f));
    (share, eased)
}

impl Window {
    /// A step at `tick` in `dir`: the eased acceleration between the last two windows when one
    /// ends (0 otherwise). A reversal starts a new window and forgets the last one.
    fn step(&mut self, tick: u64, dir: i8, f: f64) -> f64 {
        if dir != self.dir || self.steps == 0 {
            let last = if dir == self.dir { self.last } else { None };
            *self = Window {
                start: tick,
                steps: 0,
                dir,
                last,
            };
        }
        self.steps += 1;
        let len = (tick - self.start) as f64;
        if len < WINDOW_S * f {
            return 0.0;
        }
        // The intervals from the window's first step to this one.
        let n = f64::from(dir) * f64::from(self.steps - 1);
        let accel = self.last.map_or(0.0, |(m, l)| {
            let (u, v) = (m * f / l, n * f / len);
            // Each window's length a tick towards the speed of the other.
            let towards = |own: f64, other: f64, ticks: f64| {
                if libm::fabs(own) > libm::fabs(other) {
                    ticks + 1.0
                } else {
                    ticks - 1.0
                }
            };
            let (l1, l2) = (towards(u, v, l), towards(v, u, len));
            let eased = libm::fabs(n * f / l2 - m * f / l1);
            eased / ((l1 + l2) / (2.0 * f))
        });
        self.last = Some((n, len));
        self.start = tick;
        self.steps = 1;
        accel
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(ticks: u32, dir: i8) -> StepEvent {
        StepEvent {
            ticks,
            step: [true, false],
            dir: [dir, 1],
        }
    }

    #[test]
    fn a_train_past_a_limit_is_caught() {
        let cfg = crate::testbench::config();
        // 16 000 steps/s at most: 62.5 ticks a step at 1 MHz.
        let mut fast = TrainCheck::new(cfg, [100, 0]);
        assert!(matches!(
            fast.push(&ev(62, 1)),
            Err(Violation::Speed {
                axis: Axis::Insertion,
                ..
            })
        ));
        // 80 000 steps/s² from rest: the first step no sooner than √(2/A) = 5 000 ticks.
        let mut jump = TrainCheck::new(cfg, [100, 0]);
        assert_eq!(jump.push(&ev(5000, 1)), Ok(()));
        assert!(matches!(
            jump.push(&ev(1000, 1)),
            Err(Violation::Accel { .. })
        ));
        let mut reverse = TrainCheck::new(cfg, [100, 0]);
        assert_eq!(reverse.push(&ev(5000, 1)), Ok(()));
        assert!(matches!(reverse.push(&ev(5000, -1)), Ok(())));
        assert!(matches!(
            reverse.push(&ev(2000, 1)),
            Err(Violation::Accel { .. })
        ));
        let mut edge = TrainCheck::new(cfg, [0, 0]);
        assert!(matches!(
            edge.push(&ev(6000, -1)),
            Err(Violation::SoftLimit { .. })
        ));
    }
}
