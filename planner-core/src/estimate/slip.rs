//! The insertion the tip did not follow. A membrane holds the tip while the needle is pushed (a
//! stall), then gives (the tip jumps the stalled length): the fixes show it as progress along
//! the heading millimetres short of the insertion commanded over the last few millimetres. Taken
//! between two fixes, the progress cancels the errors no single fix shows (the registration, the
//! field's bias), which are the same in both.

use crate::model::kinematics::V3;

/// Fused fixes kept (a reading comes after every push and every turn of the bevel: two or more
/// a millimetre).
const WINDOW: usize = 8;

/// The least commanded insertion the progress is measured over (mm): about four times the
/// spread of the difference of two fixes along the heading (0.7 mm at the default 0.5 mm per
/// axis).
const SPAN_MM: f32 = 3.0;

/// The least insertion between two kept fixes (mm). A reading comes after every turn of the bevel
/// as well as after every push, at the insertion of the one before it: kept, eight of them
/// spanned 2 mm, under [`SPAN_MM`], and a stall while the steering turned at every push went
/// unseen (the tip held, counted as lost, 34 mm from the target).
const SPACING_MM: f32 = 0.5;

/// The last fused fixes, each with the insertion commanded when it was taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slip {
    fixes: [(V3, f32); WINDOW],
    len: usize,
    next: usize,
    inserted: f32,
}

impl Slip {
    /// No fix yet.
    pub const NONE: Slip = Slip {
        fixes: [(V3::new(0.0, 0.0, 0.0), 0.0); WINDOW],
        len: 0,
        next: 0,
        inserted: 0.0,
    };

    /// The needle was pushed `length` mm.
    pub fn advanced(&mut self, length: f32) {
        if length.is_finite() {
            self.inserted += length;
        }
    }

    /// How much farther along `heading` the fix `z` is than the insertion commanded since the
    /// newest fused fix at least [`SPAN_MM`] of insertion back (mm; negative: the tip was held
    /// back). 0 while no fix is that far back.
    pub fn slip(&self, z: V3, heading: V3) -> f32 {
        let from = self.fixes[..self.len]
            .iter()
            .filter(|(_, at)| self.inserted - at >= SPAN_MM)
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((old, at)) = from else {
            return 0.0;
        };
        let s = (z - old).dot(&heading) - (self.inserted - at);
        if s.is_finite() {
            s
        } else {
            0.0
        }
    }

    /// The fixes are read in a frame moved by `by` from now on: the kept ones move with it.
    pub fn moved(&mut self, by: V3) {
        for (z, _) in &mut self.fixes[..self.len] {
            *z += by;
        }
    }

    /// The fix `z` was fused.
    pub fn fused(&mut self, z: V3) {
        let newest = self.fixes[(self.next + WINDOW - 1) % WINDOW].1;
        if self.len > 0 && self.inserted - newest < SPACING_MM {
            return;
        }
        self.fixes[self.next] = (z, self.inserted);
        self.next = (self.next + 1) % WINDOW;
        self.len = (self.len + 1).min(WINDOW);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fixes every half millimetre of a tip that follows the insertion until `held_from`, then
    /// stays there.
    fn pushed(held_from: f32, to: f32) -> (Slip, V3) {
        let heading = V3::new(0.0, 0.6, 0.8);
        let mut s = Slip::NONE;
        let mut depth = 0.0;
        let mut tip = V3::new(1.0, 2.0, 3.0);
        while depth < to {
            s.advanced(0.5);
            depth += 0.5;
            if depth <= held_from {
                tip += heading * 0.5;
            }
            s.fused(tip);
        }
        (s, heading)
    }

    #[test]
    fn a_tip_that_follows_the_insertion_has_not_slipped() {
        let (mut s, heading) = pushed(100.0, 20.0);
        let tip = s.fixes[(s.next + WINDOW - 1) % WINDOW].0;
        s.advanced(0.5);
        let next = tip + heading * 0.5;
        assert!(s.slip(next, heading).abs() < 1e-4);
    }

    #[test]
    fn a_held_tip_lags_the_insertion_since_it_was_held() {
        let (mut s, heading) = pushed(10.0, 14.0);
        let held = s.fixes[(s.next + WINDOW - 1) % WINDOW].0;
        s.advanced(0.5);
        // Measured from the fix 3 mm back (at 11.5 mm, already held): 3 mm short.
        assert!(
            (s.slip(held, heading) + 3.0).abs() < 1e-3,
            "{}",
            s.slip(held, heading)
        );
        // Across the heading it is no slip.
        let across = V3::new(1.0, 0.0, 0.0);
        assert!((s.slip(held + across, heading) + 3.0).abs() < 1e-3);
    }

    #[test]
    fn nothing_is_said_before_a_fix_is_far_enough_back() {
        let (s, heading) = pushed(0.0, 2.5);
        assert_eq!(s.slip(V3::new(0.0, 0.0, 0.0), heading), 0.0);
        assert_eq!(Slip::NONE.slip(V3::new(9.0, 9.0, 9.0), heading), 0.0);
        let mut nan = s;
        nan.advanced(f32::NAN);
        nan.advanced(1.0);
        assert_eq!(nan.slip(V3::new(f32::NAN, 0.0, 0.0), heading), 0.0);
    }

    #[test]
    fn readings_after_turns_do_not_push_the_older_fixes_out() {
        // A push of half a millimetre and a turn, each read, 8 mm long; the tip held from 5 mm.
        let heading = V3::new(0.0, 0.0, 1.0);
        let mut s = Slip::NONE;
        let (mut depth, mut tip) = (0.0, V3::zeros());
        while depth < 8.0 {
            s.advanced(0.5);
            depth += 0.5;
            if depth <= 5.0 {
                tip += heading * 0.5;
            }
            s.fused(tip);
            s.fused(tip);
        }
        // The fix 3 mm back (at 5 mm) is still kept: the held tip is 3 mm short.
        assert!(
            (s.slip(tip, heading) + 3.0).abs() < 1e-3,
            "{}",
            s.slip(tip, heading)
        );
    }
}
