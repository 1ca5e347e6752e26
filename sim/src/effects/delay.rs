//! What arrives late: a tracker pose that is the tip as it was some insertion ago
//! ([`Latency`]), and imaging that sees the target at its own rate and delay ([`Imaging`]).
//! The world's clock is the insertion: time = commanded insertion / insertion speed
//! (rotations take no time in it).

use planner_core::model::kinematics::{Frame, V3};
use std::collections::VecDeque;

/// The tip frames of the last insertion, by commanded depth, to read the tip as it was
/// `lag_mm` of insertion ago.
#[derive(Clone, Debug)]
pub struct Latency {
    lag_mm: f32,
    history: VecDeque<(f32, Frame)>,
}

fn lerp(a: V3, b: V3, w: f32) -> V3 {
    a + (b - a) * w
}

/// The frame a share `w` of the way from `a` to `b`: position and axes interpolated, the
/// axes made orthonormal again (frames 1 mm apart differ by under a degree).
fn between(a: &Frame, b: &Frame, w: f32) -> Frame {
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
    /// A latency of `lag_mm` of insertion, starting with the tip at `tip`.
    pub fn new(lag_mm: f32, tip: Frame) -> Latency {
        Latency {
            lag_mm,
            history: VecDeque::from([(0.0, tip)]),
        }
    }

    /// The tip is at `tip` with `commanded` mm inserted (after a piece or a rotation).
    pub fn record(&mut self, commanded: f32, tip: Frame) {
        self.history.push_back((commanded, tip));
        let oldest_needed = commanded - self.lag_mm;
        while self.history.len() > 2 && self.history[1].0 <= oldest_needed {
            self.history.pop_front();
        }
    }

    /// The tip as it was when `commanded - lag` mm were inserted (the first frame before
    /// that; `now` if there is no history).
    pub fn seen(&self, commanded: f32, now: &Frame) -> Frame {
        let at = commanded - self.lag_mm;
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
    /// Insertion speed (mm/s): the world's clock.
    speed: f32,
    /// The last image shown (its index), if any.
    last: Option<i64>,
    /// The true target by time (s).
    history: VecDeque<(f32, V3)>,
}

impl Imaging {
    /// Imaging at `hz` (0: every reading), `delay_s` late, at insertion `speed` mm/s, of a
    /// target at `target` at the start.
    pub fn new(hz: f32, delay_s: f32, speed: f32, target: V3) -> Imaging {
        Imaging {
            hz,
            delay_s,
            speed,
            last: None,
            history: VecDeque::from([(0.0, target)]),
        }
    }

    /// The true target is at `target` with `commanded` mm inserted.
    pub fn record(&mut self, commanded: f32, target: V3) {
        let t = commanded / self.speed;
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

    /// The target a reading with `commanded` mm inserted carries: the newest image that has
    /// arrived since the last reading, showing the target where it was when it was taken;
    /// `None` when no new image arrived.
    pub fn seen(&mut self, commanded: f32) -> Option<V3> {
        let now = commanded / self.speed;
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
