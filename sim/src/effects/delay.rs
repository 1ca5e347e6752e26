//! What arrives late: a tracker pose that is the tip as it was some time ago ([`Latency`]), and
//! imaging that sees the target at its own rate and delay ([`Imaging`]). The world's clock
//! (kept by the run's effects, `state.rs`) runs with the robot: insertion at the insertion speed,
//! rotations at the driver's rotation speed; during a push a latency is speed × latency mm of
//! insertion.

use planner_core::model::kinematics::{Frame, V3};
use std::collections::VecDeque;

/// The tip frames of the last moments, by time, to read the tip as it was `lag_s` ago.
#[derive(Clone, Debug)]
pub struct Latency {
    lag_s: f32,
    history: VecDeque<(f32, Frame)>,
}

fn lerp(a: V3, b: V3, w: f32) -> V3 {
    a + (b - a) * w
}

/// The frame a share `w` of the way from `a` to `b`: a rotation's (the same point, the bevel
/// rolled) by the share of the roll, the shorter way round; a push's by position and axes
/// interpolated, the axes made orthonormal again (frames 1 mm apart differ by under a degree).
fn between(a: &Frame, b: &Frame, w: f32) -> Frame {
    if a.p == b.p {
        let (e2a, e2b) = (a.e2(), b.e2());
        let roll = libm::atan2f(e2a.cross(&e2b).dot(&a.e3()), e2a.dot(&e2b));
        return a.rolled(w * roll);
    }
    let e3 = lerp(a.e3(), b.e3(), w).normalize();
    let e2 = lerp(a.e2(), b.e2(), w);
    let e2 = (e2 - e3 * e2.dot(&e3)).normalize();
    let e1 = e2.cross(&e3);
    let mut f = *a;
    f.p = lerp(a.p, b.p, w);
    for (i, e) in [e1, e2, e3].iter().enumerate() {
        f.r.set_column(i, e);
    }
    f
}

impl Latency {
    /// A latency of `lag_s`, starting with the tip at `tip`.
    pub fn new(lag_s: f32, tip: Frame) -> Latency {
        Latency {
            lag_s,
            history: VecDeque::from([(0.0, tip)]),
        }
    }

    /// The tip is at `tip` at time `t` (s; after a piece or a rotation).
    pub fn record(&mut self, t: f32, tip: Frame) {
        self.history.push_back((t, tip));
        let oldest_needed = t - self.lag_s;
        while self.history.len() > 2 && self.history[1].0 <= oldest_needed {
            self.history.pop_front();
        }
    }

    /// The tip as it was at `t - lag` (the first frame before that; `now` if there is no
    /// history).
    pub fn seen(&self, t: f32, now: &Frame) -> Frame {
        let at = t - self.lag_s;
        match self.history.iter().position(|(c, _)| *c > at) {
            Some(0) => self.history.front().map_or(*now, |h| h.1),
            None => self.history.back().map_or(*now, |h| h.1),
            Some(i) => {
                let (ca, a) = self.history[i - 1];
                let (cb, b) = self.history[i];
                between(&a, &b, (at - ca) / (cb - ca))
            }
        }
    }
}

/// Imaging of the target at its own rate and delay.
#[derive(Clone, Debug)]
pub struct Imaging {
    /// Images per second (0: one at every reading).
    hz: f32,
    /// Age of an image when it arrives (s).
    delay_s: f32,
    /// The last image shown (its index), if any.
    last: Option<i64>,
    /// The true target by time (s).
    history: VecDeque<(f32, V3)>,
}

impl Imaging {
    /// Imaging at `hz` (0: every reading), `delay_s` late, of a target at `target` at the
    /// start.
    pub fn new(hz: f32, delay_s: f32, target: V3) -> Imaging {
        Imaging {
            hz,
            delay_s,
            last: None,
            history: VecDeque::from([(0.0, target)]),
        }
    }

    /// The true target is at `target` at time `t` (s).
    pub fn record(&mut self, t: f32, target: V3) {
        self.history.push_back((t, target));
        let oldest_needed = t - self.delay_s - if self.hz > 0.0 { 1.0 / self.hz } else { 0.0 };
        while self.history.len() > 2 && self.history[1].0 <= oldest_needed {
            self.history.pop_front();
        }
    }

    fn target_at(&self, t: f32) -> V3 {
        self.history
            .iter()
            .rev()
            .find(|(ti, _)| *ti <= t)
            .or(self.history.front())
            .map_or_else(V3::zeros, |(_, p)| *p)
    }

    /// The target a reading at time `now` (s) carries: the newest image that has arrived
    /// since the last reading, showing the target where it was when it was taken; `None` when
    /// no new image arrived.
    pub fn seen(&mut self, now: f32) -> Option<V3> {
        let taken = now - self.delay_s;
        if self.hz <= 0.0 {
            return Some(self.target_at(taken));
        }
        if taken < 0.0 {
            return None;
        }
        let k = libm::floorf(taken * self.hz) as i64;
        if self.last.is_some_and(|l| l >= k) {
            return None;
        }
        self.last = Some(k);
        Some(self.target_at(k as f32 / self.hz))
    }
}
