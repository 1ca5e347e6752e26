//! A segment's two axes merged into one train of step events for the timer interrupt.

use crate::config::{Axis, MotionConfig};
use crate::moves::SegmentTarget;
use crate::profile::AxisRun;

/// What the timer does next: wait `ticks`, then pulse the axes marked in `step`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepEvent {
    /// Ticks from the previous event (or the segment's start).
    pub ticks: u32,
    /// Which axes step ([`Axis`] order).
    pub step: [bool; 2],
    /// Direction of each axis: +1 or −1 (set before the pulse).
    pub dir: [i8; 2],
}

/// Both axes of one segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentRun {
    axes: [AxisRun; 2],
    /// Ticks until each axis' next step (`None`: it has none left).
    wait: [Option<u32>; 2],
    /// Whether an event has been given.
    started: bool,
}

impl SegmentRun {
    /// Nothing to do.
    pub const IDLE: SegmentRun = SegmentRun {
        axes: [AxisRun::IDLE; 2],
        wait: [None; 2],
        started: false,
    };

    /// From `from` (steps) to `seg`'s target: both axes on the same profile shape (each at its
    /// share of the segment), the shape's speed and acceleration the least any axis allows.
    pub fn new(cfg: &MotionConfig, from: [i32; 2], seg: &SegmentTarget) -> SegmentRun {
        let f = cfg.tick_hz as f32;
        let steps = [0, 1].map(|i| seg.target[i].saturating_sub(from[i]));
        let mut rate = seg.rate;
        let mut accel = f32::INFINITY;
        for axis in Axis::BOTH {
            let n = steps[axis as usize].unsigned_abs() as f32;
            if n == 0.0 {
                continue;
            }
            let a = &cfg.axes[axis as usize];
            // One tick under the top speed, so the floored intervals never pass it.
            let top = f / (f / (a.max_speed * a.steps_per_unit) + 1.0);
            rate = rate.min(top / n);
            accel = accel.min(a.max_accel * a.steps_per_unit / n);
        }
        let mut run = SegmentRun::IDLE;
        for i in 0..2 {
            let n = steps[i].unsigned_abs() as f32;
            run.axes[i] = AxisRun::new(steps[i], n * rate, n * accel, f);
            run.wait[i] = run.axes[i].next_interval();
        }
        run
    }

    /// Whether every step has been given.
    pub fn is_done(&self) -> bool {
        self.wait == [None, None]
    }

    /// The next step event; `None` when the segment is done. Constant work.
    pub fn next_event(&mut self) -> Option<StepEvent> {
        let dt = match self.wait {
            [Some(a), Some(b)] => a.min(b),
            [Some(a), None] => a,
            [None, Some(b)] => b,
            [None, None] => return None,
        };
        self.started = true;
        let mut step = [false; 2];
        for (i, s) in step.iter_mut().enumerate() {
            if let Some(w) = self.wait[i] {
                if w == dt {
                    *s = true;
                    self.wait[i] = self.axes[i].next_interval();
                } else {
                    self.wait[i] = Some(w - dt);
                }
            }
        }
        Some(StepEvent {
            ticks: dt,
            step,
            dir: [self.axes[0].dir(), self.axes[1].dir()],
        })
    }

    /// Decelerate both axes to rest as fast as each may (the same share of the segment: both
    /// follow the same shape); at once when no step has been given yet.
    pub fn stop(&mut self) {
        if !self.started {
            *self = SegmentRun::IDLE;
            return;
        }
        for a in &mut self.axes {
            a.stop();
        }
    }
}

impl SegmentRun {
    /// Direction of each axis.
    pub fn dir(&self) -> [i8; 2] {
        [self.axes[0].dir(), self.axes[1].dir()]
    }

    /// Steps still to give per axis (the one already timed included).
    pub fn steps_left(&self) -> [u32; 2] {
        [0, 1].map(|i| self.axes[i].remaining() + u32::from(self.wait[i].is_some()))
    }
}
