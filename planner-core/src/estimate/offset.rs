//! The tracker's offset from the imaging frame, read near the entry. The registration and the
//! field's distortion move every fix by an error no fix shows by itself. Near the entry the
//! insertion shows it: the robot knows where it started the needle (to the entry's spread), and
//! the tip has gone only the few millimetres it was pushed, along headings the fixes keep
//! measured. So the fixes' distance from the path reckoned from the entry is the offset plus the
//! entry's error: across the heading their mean; along it their median, because a membrane that
//! holds the tip (a stall) moves the fixes back only while it holds, and then the tip jumps to
//! where it was pushed.
//!
//! Once read, the offset (shrunk by what the entry's spread and the fixes' noise leave of it) is
//! taken off every later fix. The offset seen near the entry is not the one at the target (a
//! registration's rotation, a field's modes), so the steering keeps the whole of
//! `registration_mm` clear of the obstacles as before; the target is aimed with less of it.

use super::noise::NoiseModel;
use crate::model::kinematics::V3;

/// The insertion over which the fixes are read (mm): the path reckoned from the entry drifts by
/// a few hundredths of a millimetre over it, and it holds about 20 fixes.
const READ_OVER_MM: f32 = 15.0;

/// The fixes' distances along the heading kept for the median: one a millimetre over
/// [`READ_OVER_MM`] (readings come about two a millimetre; every one kept would double the
/// estimate the device copies while it steers).
const ALONG_KEPT: usize = 16;

/// The least insertion between two distances kept along the heading (mm).
const ALONG_SPACING_MM: f32 = 0.9;

/// The variance of a median of normal draws over that of their mean (π/2).
const MEDIAN_VARIANCE: f32 = 1.571;

/// The fewest fixes read before the offset is taken off (dropouts may leave fewer).
const FEWEST_FIXES: u16 = 5;

/// Fixes farther than this many standard deviations (squared, over the two axes across) from
/// the reckoned path are not read (outliers).
const GATE: f32 = 25.0;

/// The largest scatter of the fixes about their mean distance from the reckoned path that reads
/// as an offset (per axis, in units of a fix's variance): twice the tracker's noise, as for a
/// lost tip. More, and the path itself drifted against the fixes (a heading the fixes could
/// not hold: at twice the world one run read 1.8 mm the wrong way and met a sphere), or the
/// tracker is noisier than the steering was told: nothing is read.
const MOST_SCATTER: f32 = 2.0;

/// The largest mean distance from the reckoned path that reads as an offset (squared, in units
/// of the offset's and the entry's variance per axis): about the 99.9th percentile of two axes.
/// Farther, it is not the offset told of. At the 99th percentile a true offset of 3.3 standard
/// deviations went unread, and its run touched a sphere (space-clinical, seed 3268).
const MOST_OFFSET: f32 = 13.8;

/// The tracker's offset: read from the fixes near the entry, then taken off every fix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerOffset {
    /// The tip as the insertion alone puts it: the entry moved by the estimate's own steps,
    /// never by a fix.
    reckoned: V3,
    /// Insertion so far (mm).
    inserted: f32,
    /// Sum of the fixes' distances from the reckoned tip across the heading, and their count.
    sum: V3,
    count: u16,
    /// Sum of their squares, per axis.
    sum_sq: V3,
    /// The fixes' distances from the reckoned tip along the heading, one a millimetre, and the
    /// insertion of the last kept.
    along: [f32; ALONG_KEPT],
    alongs: usize,
    along_at: f32,
    /// The offset taken off the fixes, once read.
    read: Option<V3>,
    /// Variances per axis (mm²): the offset's prior (`registration_mm`), the entry's, a fix's.
    prior: f32,
    entry: f32,
    fix: f32,
}

impl TrackerOffset {
    /// Before the insertion, the tip at `entry`. Without a hidden error told
    /// (`registration_mm` 0) nothing is ever read and every fix is left as it is.
    pub fn new(entry: V3, noise: &NoiseModel) -> TrackerOffset {
        TrackerOffset {
            reckoned: entry,
            inserted: 0.0,
            sum: V3::zeros(),
            count: 0,
            sum_sq: V3::zeros(),
            along: [0.0; ALONG_KEPT],
            alongs: 0,
            along_at: f32::NEG_INFINITY,
            read: None,
            prior: noise.registration_mm * noise.registration_mm,
            entry: noise.entry_position_mm * noise.entry_position_mm,
            fix: noise.position_mm * noise.position_mm,
        }
    }

    /// The estimate stepped by `moved` over `length` mm of insertion.
    pub fn advanced(&mut self, moved: V3, length: f32) {
        if moved.iter().all(|v| v.is_finite()) && length.is_finite() {
            self.reckoned += moved;
            self.inserted += length;
        }
    }

    /// The offset taken off the fixes (zero until read).
    pub fn offset(&self) -> V3 {
        self.read.unwrap_or_else(V3::zeros)
    }

    /// The fix `z` (the tip heading along `heading`) as the imaging frame has it: `z` less the
    /// offset once read. Near the entry the fix is read; the first fix past
    /// [`READ_OVER_MM`] reads the offset, and it is returned as `Some` that once (the estimate
    /// moves by it).
    pub fn corrected(&mut self, z: V3, heading: V3) -> (V3, Option<V3>) {
        if let Some(o) = self.read {
            return (z - o, None);
        }
        if !(self.prior > 0.0) || !z.iter().all(|v| v.is_finite()) {
            return (z, None);
        }
        if self.inserted < READ_OVER_MM {
            let d = z - self.reckoned;
            let across = d - heading * d.dot(&heading);
            if across.dot(&across) <= GATE * (self.prior + self.entry + self.fix) {
                self.sum += across;
                self.sum_sq += across.component_mul(&across);
                self.count = self.count.saturating_add(1);
                let spaced = self.inserted - self.along_at >= ALONG_SPACING_MM;
                if let (true, Some(slot)) = (spaced, self.along.get_mut(self.alongs)) {
                    *slot = d.dot(&heading);
                    self.alongs += 1;
                    self.along_at = self.inserted;
                }
            }
            return (z, None);
        }
        let n = f32::from(self.count).max(1.0);
        let raw = self.sum / n;
        // The fixes' scatter about their mean, on the axis it is widest.
        let scatter = (self.sum_sq / n - raw.component_mul(&raw)).max();
        let steady = scatter <= MOST_SCATTER * self.fix;
        let mean = raw - heading * raw.dot(&heading);
        let plausible = mean.dot(&mean) <= MOST_OFFSET * (self.prior + self.entry);
        if self.count < FEWEST_FIXES || !steady || !plausible {
            // Never read: the fixes are left as they are.
            self.prior = 0.0;
            return (z, None);
        }
        let shrink = self.prior / (self.prior + self.entry + self.fix / n);
        let mut o = mean * shrink;
        let kept = &mut self.along[..self.alongs];
        sort(kept);
        if let Some(&median) = kept.get(kept.len() / 2) {
            let spread = MEDIAN_VARIANCE * self.fix / kept.len() as f32;
            let shrink = self.prior / (self.prior + self.entry + spread);
            if median * median <= MOST_OFFSET * (self.prior + self.entry) {
                o += heading * (median * shrink);
            }
        }
        self.read = Some(o);
        (z - o, Some(o))
    }
}

/// Insertion sort: a few values, once an insertion. Core's sort cost the device 4.8 KiB more
/// flash.
fn sort(values: &mut [f32]) {
    for i in 1..values.len() {
        let mut j = i;
        while j > 0 && values[j - 1] > values[j] {
            values.swap(j - 1, j);
            j -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn told(registration_mm: f32) -> NoiseModel {
        NoiseModel {
            registration_mm,
            ..NoiseModel::DEFAULT
        }
    }

    /// A straight insertion along z with fixes moved by `off`, one a millimetre: the fix at 20
    /// mm as corrected, and what was read.
    fn insert(noise: &NoiseModel, off: V3) -> (V3, Option<V3>) {
        let mut o = TrackerOffset::new(V3::zeros(), noise);
        let heading = V3::z();
        let mut out = (V3::zeros(), None);
        for k in 1..=20 {
            o.advanced(heading, 1.0);
            let (z, read) = o.corrected(V3::new(0.0, 0.0, k as f32) + off, heading);
            if read.is_some() {
                out.1 = read;
            }
            out.0 = z;
        }
        out
    }

    #[test]
    fn an_offset_is_read_near_the_entry_and_taken_off_later_fixes() {
        let off = V3::new(0.5, -0.4, 0.3);
        let (z, read) = insert(&told(0.42), off);
        let read = read.expect("read once past the entry's millimetres");
        // Read from the 14 fixes before 15 mm, shrunk by what the entry's spread and their noise
        // leave: 0.42² / (0.42² + 0.2² + 0.5² / 14), along the heading for a median.
        let shrink = |spread: f32| 0.42f32 * 0.42 / (0.42 * 0.42 + 0.04 + spread * 0.25 / 14.0);
        let expected = V3::new(0.5 * shrink(1.0), -0.4 * shrink(1.0), 0.3 * shrink(1.571));
        assert!((read - expected).norm() < 1e-5, "{read:?}");
        assert!((z - V3::new(0.0, 0.0, 20.0) - (off - read)).norm() < 1e-5);
        assert!(
            (z - V3::new(0.0, 0.0, 20.0)).norm() < 0.3 * off.norm(),
            "{z:?}"
        );
    }

    #[test]
    fn a_stall_near_the_entry_does_not_read_as_an_offset_along_the_heading() {
        // Fixes 0.3 mm ahead of the reckoned path but for four held 1 mm back (a membrane at
        // 6 mm), then the tip jumps back onto it.
        let mut o = TrackerOffset::new(V3::zeros(), &told(0.42));
        let mut read = None;
        for k in 1..=16 {
            o.advanced(V3::z(), 1.0);
            let held = if (6..10).contains(&k) { -1.0 } else { 0.0 };
            let z = V3::new(0.0, 0.0, k as f32 + 0.3 + held);
            read = read.or(o.corrected(z, V3::z()).1);
        }
        let read = read.expect("read");
        let shrink = 0.42f32 * 0.42 / (0.42 * 0.42 + 0.04 + 1.571 * 0.25 / 14.0);
        assert!((read.z - 0.3 * shrink).abs() < 1e-5, "{read:?}");
    }

    #[test]
    fn without_a_hidden_error_told_fixes_are_left_as_they_are() {
        let off = V3::new(0.5, -0.4, 0.3);
        let (z, read) = insert(&told(0.0), off);
        assert_eq!(read, None);
        assert_eq!(z, V3::new(0.0, 0.0, 20.0) + off);
    }

    #[test]
    fn too_few_fixes_near_the_entry_read_nothing() {
        let noise = told(0.42);
        let mut o = TrackerOffset::new(V3::zeros(), &noise);
        for k in 1..=20 {
            o.advanced(V3::z(), 1.0);
            // A dropout over the first 12 mm: three fixes before 15 mm.
            if (13..15).contains(&k) || k > 15 {
                let z = V3::new(0.5, 0.0, k as f32);
                let (c, read) = o.corrected(z, V3::z());
                assert_eq!((c, read), (z, None), "fix at {k} mm");
            }
        }
        assert_eq!(o.offset(), V3::zeros());
    }

    #[test]
    fn a_far_fix_near_the_entry_is_not_read() {
        let noise = told(0.42);
        let mut o = TrackerOffset::new(V3::zeros(), &noise);
        let mut read = None;
        for k in 1..=16 {
            o.advanced(V3::z(), 1.0);
            // One outlier 8 mm off among fixes 0.3 mm off.
            let x = if k == 5 { 8.0 } else { 0.3 };
            read = read.or(o.corrected(V3::new(x, 0.0, k as f32), V3::z()).1);
        }
        let read = read.expect("read");
        assert!(read.x > 0.0 && read.x < 0.3, "{read:?}");
    }

    #[test]
    fn non_finite_input_changes_nothing() {
        let noise = told(0.42);
        let mut o = TrackerOffset::new(V3::zeros(), &noise);
        let before = o;
        o.advanced(V3::new(f32::NAN, 0.0, 0.0), 1.0);
        let z = V3::new(f32::INFINITY, 0.0, 0.0);
        let (c, read) = o.corrected(z, V3::z());
        assert_eq!((o, read), (before, None));
        assert!(c.x.is_infinite());
    }

    /// Fixes `off` from a straight insertion along z up to 20 mm, each moved across by
    /// `scatter(k)` more: what was read.
    fn read(off: V3, scatter: impl Fn(usize) -> V3) -> Option<V3> {
        let mut o = TrackerOffset::new(V3::zeros(), &told(0.42));
        let mut read = None;
        for k in 1..=20 {
            o.advanced(V3::z(), 1.0);
            let z = V3::new(0.0, 0.0, k as f32) + off + scatter(k);
            read = read.or(o.corrected(z, V3::z()).1);
        }
        read
    }

    #[test]
    fn an_implausible_offset_or_fixes_that_wander_read_nothing() {
        let small = V3::new(0.5, -0.4, 0.0);
        let still = |_| V3::zeros();
        assert!(read(small, still).is_some());
        // Fixes 0.5 mm either side of the offset: within the tracker's told noise, read.
        let told_noise = |k: usize| V3::new(if k.is_multiple_of(2) { 0.5 } else { -0.5 }, 0.0, 0.0);
        assert!(read(small, told_noise).is_some());
        // A path that drifts from the fixes by 0.2 mm a millimetre: not an offset.
        let drift = |k: usize| V3::new(0.2 * k as f32 - 1.5, 0.0, 0.0);
        assert_eq!(read(small, drift), None);
        // 2 mm across: beyond 3.7 standard deviations of 0.42 mm and the entry's 0.2.
        assert_eq!(read(V3::new(2.0, 0.0, 0.0), still), None);
    }

    #[test]
    fn the_sort_orders_a_few_values() {
        let mut v = [3.0, -1.0, 2.5, 0.0, -1.0, 9.0];
        sort(&mut v);
        assert_eq!(v, [-1.0, -1.0, 0.0, 2.5, 3.0, 9.0]);
    }
}
