//! One axis' step timing within a segment: a trapezoidal profile evaluated step by step.
//!
//! The interval before step `j` of `n` is the largest of three: the constant-acceleration curve
//! from rest (`K / (√j + √(j−1))`, `K = f·√(2/A)` ticks), its mirror towards the end
//! (`K / (√(n−j+1) + √(n−j))`) and the cruise interval. The speed is therefore the least of the
//! three curves at every step: a trapezoid, or a triangle where cruise is never reached, found
//! without computing where the phases meet. The differences of square roots are written as
//! quotients so nothing cancels in `f32`; each interval is floored and its fraction carried to
//! the next, so the step times stay within one tick of the ideal ones over any length. Only
//! correctly rounded operations (add, divide, square root) are used: the same bits on any IEEE
//! machine, the host and the Cortex-M4F alike.

// The square roots of the step timing are correctly rounded, so the same bits everywhere; they
// are software on the M4F, which is why they are to leave the step path.
#![allow(clippy::disallowed_methods)]

/// One axis' steps in one segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisRun {
    /// Steps in the segment.
    total: u32,
    /// Steps already given.
    done: u32,
    /// `f·√(2/A)` (ticks).
    k: f32,
    /// Ticks per step at cruise.
    cruise: f32,
    /// The fraction of a tick carried to the next interval.
    carry: f32,
    /// The last interval before flooring (ticks).
    last: f32,
    /// Direction: +1 or −1.
    dir: i8,
    /// `√done`, the acceleration curve's root the next interval shares with this one; `None`
    /// once the curve is below cruise for good (it only falls).
    root_done: Option<f32>,
    /// `(r, √r)` for the steps left after the next one: the deceleration curve's root the next
    /// interval shares with this one (a stop changes the steps left, and misses it).
    root_left: Option<(u32, f32)>,
}

impl AxisRun {
    /// No steps.
    pub const IDLE: AxisRun = AxisRun {
        total: 0,
        done: 0,
        k: 0.0,
        cruise: 0.0,
        carry: 0.0,
        last: 0.0,
        dir: 1,
        root_done: Some(0.0),
        root_left: None,
    };

    /// `steps` (signed) at cruise speed `speed` and acceleration `accel` (steps/s, steps/s²,
    /// both positive and finite) with a timer of `tick_hz`.
    pub fn new(steps: i32, speed: f32, accel: f32, tick_hz: f32) -> AxisRun {
        if steps == 0 {
            return AxisRun::IDLE;
        }
        AxisRun {
            total: steps.unsigned_abs(),
            done: 0,
            k: tick_hz * libm::sqrtf(2.0 / accel),
            cruise: tick_hz / speed,
            carry: 0.0,
            last: 0.0,
            dir: if steps > 0 { 1 } else { -1 },
            root_done: Some(0.0),
            root_left: None,
        }
    }

    /// Direction of the steps: +1 or −1.
    pub fn dir(&self) -> i8 {
        self.dir
    }

    /// Steps still to give.
    pub fn remaining(&self) -> u32 {
        self.total - self.done
    }

    /// Ticks from the previous step (or the segment's start) to the next one; `None` when done.
    pub fn next_interval(&mut self) -> Option<u32> {
        if self.done >= self.total {
            return None;
        }
        // The same roots as `k / (√j + √(j−1))` and `k / (√r + √(r−1))` each time, each taken
        // once: the interrupt's work is two square roots a step at most, one at cruise.
        let up = match self.root_done {
            Some(below) => {
                let root = libm::sqrtf((self.done + 1) as f32);
                let up = self.k / (root + below);
                // Non-increasing in the step (correctly rounded roots, sum and quotient are
                // monotonic): once at or below cruise, never again above it.
                self.root_done = (up > self.cruise).then_some(root);
                up
            }
            None => 0.0,
        };
        let r = self.total - self.done;
        let root_r = match self.root_left {
            Some((left, root)) if left == r => root,
            _ => libm::sqrtf(r as f32),
        };
        let root_below = libm::sqrtf((r - 1) as f32);
        self.root_left = Some((r - 1, root_below));
        let down = self.k / (root_r + root_below);
        let x = up.max(down).max(self.cruise);
        self.last = x;
        let with_carry = x + self.carry;
        let ticks = libm::floorf(with_carry);
        self.carry = with_carry - ticks;
        self.done += 1;
        // Saturating: an interval past u32 (over an hour at 1 MHz) is not reachable with a
        // validated configuration.
        Some(ticks as u32)
    }

    /// Cut the segment short so that it decelerates to rest as fast as allowed from the speed
    /// it has now (at once when it has not started).
    pub fn stop(&mut self) {
        if self.done == 0 {
            self.total = 0;
            return;
        }
        // The end curve's interval at r steps from the end is at most K / (2√(r−1)): with
        // r − 1 ≥ (K / 2c)² it is no longer than the current interval c, so the speed never jumps.
        let q = self.k / (2.0 * self.last);
        let r = libm::ceilf(q * q) + 1.0;
        let r = if r < (self.total - self.done) as f32 {
            r as u32
        } else {
            self.total - self.done
        };
        self.total = self.done + r;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn intervals(mut run: AxisRun) -> heapless::Vec<u32, 4096> {
        let mut v = heapless::Vec::new();
        while let Some(t) = run.next_interval() {
            v.push(t).unwrap();
        }
        v
    }

    #[test]
    fn a_long_move_accelerates_cruises_and_decelerates_symmetrically() {
        // 2000 steps at 1000 steps/s, 10 000 steps/s²: 50 steps to reach cruise.
        let v = intervals(AxisRun::new(2000, 1000.0, 10_000.0, 1e6));
        assert_eq!(v.len(), 2000);
        assert!(v[0] > v[10] && v[10] > v[40]);
        assert!(v[100..1900].iter().all(|&t| t == 1000));
        // First step from rest: √(2/A) s = 14 142 ticks.
        assert_eq!(v[0], 14_142);
        let (a, b) = (v[..50].iter().sum::<u32>(), v[1950..].iter().sum::<u32>());
        assert!(a.abs_diff(b) <= 1, "{a} {b}");
    }

    /// Each interval straight from the formula, every root taken anew.
    fn direct(
        total: u32,
        k: f32,
        cruise: f32,
        stop_after: Option<u32>,
    ) -> heapless::Vec<u32, 4096> {
        let (mut v, mut carry, mut total) = (heapless::Vec::new(), 0.0f32, total);
        let mut done = 0;
        while done < total {
            let j = (done + 1) as f32;
            let up = k / (libm::sqrtf(j) + libm::sqrtf(j - 1.0));
            let r = (total - done) as f32;
            let down = k / (libm::sqrtf(r) + libm::sqrtf(r - 1.0));
            let x = up.max(down).max(cruise);
            let ticks = libm::floorf(x + carry);
            carry = x + carry - ticks;
            done += 1;
            v.push(ticks as u32).unwrap();
            if Some(done) == stop_after {
                let q = k / (2.0 * x);
                let r = libm::ceilf(q * q) + 1.0;
                total = done
                    + if r < (total - done) as f32 {
                        r as u32
                    } else {
                        total - done
                    };
            }
        }
        v
    }

    #[test]
    fn the_shared_roots_give_the_formulas_intervals_bit_for_bit() {
        for (steps, speed, accel) in [
            (2000, 1000.0, 10_000.0),
            (-20, 1000.0, 10_000.0),
            (3999, 16_000.0, 80_000.0),
            (777, 1234.5, 987.0),
            (1, 50.0, 1.0),
        ] {
            for stop_after in [None, Some(1), Some(37), Some(500)] {
                let mut run = AxisRun::new(steps, speed, accel, 1e6);
                let mut got = heapless::Vec::<u32, 4096>::new();
                while let Some(t) = run.next_interval() {
                    got.push(t).unwrap();
                    if Some(got.len() as u32) == stop_after {
                        run.stop();
                    }
                }
                let want = direct(steps.unsigned_abs(), run.k, run.cruise, stop_after);
                assert_eq!(got, want, "{steps} steps, stop after {stop_after:?}");
            }
        }
    }

    #[test]
    fn a_short_move_is_a_triangle_below_cruise() {
        let v = intervals(AxisRun::new(-20, 1000.0, 10_000.0, 1e6));
        assert_eq!(v.len(), 20);
        assert!(v.iter().all(|&t| t > 1000));
        assert_eq!(AxisRun::new(-20, 1000.0, 10_000.0, 1e6).dir(), -1);
    }

    #[test]
    fn stop_decelerates_within_the_stopping_distance() {
        let mut run = AxisRun::new(2000, 1000.0, 10_000.0, 1e6);
        for _ in 0..500 {
            run.next_interval();
        }
        run.stop();
        // v²/2A = 50 steps, plus the rounding of the formula.
        assert!((50..=52).contains(&run.remaining()), "{}", run.remaining());
        let rest = intervals(run);
        assert!(rest.windows(2).all(|w| w[0] <= w[1] + 1));
        let mut fresh = AxisRun::new(10, 1000.0, 10_000.0, 1e6);
        fresh.stop();
        assert_eq!(fresh.next_interval(), None);
    }
}
