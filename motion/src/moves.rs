//! The schedule's operations and how each becomes a run of coordinated segments.
//!
//! A [`Move`] mirrors planner-core's `Op`. Each becomes one or more segments, each a straight
//! line in (insertion, rotation) step space that starts and ends at rest:
//!
//! - `Rotate`: the shaft alone, at the driver's rotation speed;
//! - `Insert`: the stage alone, at the insertion speed;
//! - `InsertSpin`: one segment per turn, the shaft turning a whole turn while the stage inserts
//!   its share, the turns alternating in direction and starting towards zero twist (as the
//!   schedule counts the twist; zero twist is the middle of the rotation's soft limits); both axes follow the same profile shape, so the spin stays tied
//!   to the insertion;
//! - `InsertDuty`: cycles of a held push (the share `duty`) and a spun push with one turn, the
//!   turns alternating; as many cycles as the spun share takes turns at the driver's spin rate,
//!   an even number (at least two) so the shaft ends where it began.
//!
//! Targets are absolute: every segment ends at the nearest step to the exact position the
//! schedule has reached, so rounding never accumulates.

use crate::config::{Axis, MotionConfig};
use crate::MotionError;

/// One command of the driver, in the schedule's units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Move {
    /// Turn the shaft by `angle_deg` (signed), no insertion.
    Rotate {
        /// Degrees.
        angle_deg: f32,
    },
    /// Push `length_mm` without rotating.
    Insert {
        /// Millimetres.
        length_mm: f32,
    },
    /// Push `length_mm` while spinning `turns` whole turns, alternating.
    InsertSpin {
        /// Millimetres.
        length_mm: f32,
        /// Whole turns.
        turns: u32,
    },
    /// Push `length_mm` duty-cycled: the share `duty` with the bevel held, the rest spun.
    InsertDuty {
        /// Millimetres.
        length_mm: f32,
        /// Share held, in [0, 1].
        duty: f32,
    },
}

/// One segment: where both axes go (absolute steps) and the nominal share of the segment done
/// per second (the profile's cruise, before the axes' limits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentTarget {
    /// Target of each axis (steps).
    pub target: [i32; 2],
    /// Nominal rate (1/s).
    pub rate: f32,
}

/// A move checked against the limits, with the state it starts from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    mv: Move,
    /// Exact positions before the move (units).
    from: [f64; 2],
    /// Segments it takes.
    parts: u32,
    /// Direction of the first spin turn: +1 or −1.
    first_dir: i8,
}

/// The exact positions the moves queued so far end at, and the checks of the next move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Planned {
    /// Exact positions (units).
    pub at: [f64; 2],
}

impl Planned {
    /// `mv` from here, checked against the soft limits; the state moves to its end.
    pub fn resolve(&mut self, cfg: &MotionConfig, mv: Move) -> Result<Resolved, MotionError> {
        let (ins_len, rot_len) = match mv {
            Move::Rotate { angle_deg } => (0.0, angle_deg),
            Move::Insert { length_mm } | Move::InsertSpin { length_mm, .. } => (length_mm, 0.0),
            Move::InsertDuty { length_mm, duty } => {
                if !(0.0..=1.0).contains(&duty) {
                    return Err(MotionError::BadMove);
                }
                (length_mm, 0.0)
            }
        };
        if !ins_len.is_finite() || !rot_len.is_finite() {
            return Err(MotionError::BadMove);
        }
        let end = [
            self.at[0] + f64::from(ins_len),
            self.at[1] + f64::from(rot_len),
        ];
        for axis in Axis::BOTH {
            let i = axis as usize;
            within(cfg, axis, cfg.to_steps(axis, end[i]))?;
        }
        let rot_now = cfg.to_steps(Axis::Rotation, self.at[1]);
        // Zero twist is the middle of the rotation's soft limits (the shaft's 0 unless a job
        // was set about another roll).
        let rot = &cfg.axes[Axis::Rotation as usize];
        let zero = cfg.to_steps(
            Axis::Rotation,
            (f64::from(rot.min) + f64::from(rot.max)) / 2.0,
        );
        let first_dir: i8 = if rot_now > zero { -1 } else { 1 };
        let parts = match mv {
            Move::Rotate { .. } | Move::Insert { .. } => 1,
            Move::InsertSpin { turns, .. } => turns.max(1),
            Move::InsertDuty { length_mm, duty } => duty_parts(cfg, length_mm, duty),
        };
        let spins = match mv {
            Move::InsertSpin { .. } => true,
            Move::InsertDuty { .. } => parts > 1,
            Move::Rotate { .. } | Move::Insert { .. } => false,
        };
        if spins {
            let swing = rot_now.saturating_add(i32::from(first_dir) * rev_steps(cfg));
            within(cfg, Axis::Rotation, swing)?;
        }
        let resolved = Resolved {
            mv,
            from: self.at,
            parts,
            first_dir,
        };
        self.at = end;
        Ok(resolved)
    }
}

fn within(cfg: &MotionConfig, axis: Axis, steps: i32) -> Result<(), MotionError> {
    let (lo, hi) = cfg.limit_steps(axis);
    if (lo..=hi).contains(&steps) {
        Ok(())
    } else {
        Err(MotionError::SoftLimit(axis))
    }
}

/// Steps of one whole turn of the shaft.
fn rev_steps(cfg: &MotionConfig) -> i32 {
    cfg.to_steps(Axis::Rotation, 360.0)
}

/// Segments of a duty-cycled push: one for a plain push (duty 1), else a held and a spun
/// segment per cycle, cycles as many as the spun share takes turns, even, at least two, and no
/// more than the push has insertion steps.
fn duty_parts(cfg: &MotionConfig, length_mm: f32, duty: f32) -> u32 {
    if duty >= 1.0 {
        return 1;
    }
    let r = &cfg.rates;
    let turns = libm::ceilf(libm::fabsf(length_mm) * (1.0 - duty) * r.spin_rev_s / r.insert_mm_s);
    let steps = libm::fabsf(length_mm) * cfg.axes[0].steps_per_unit;
    let cycles = turns.min(steps).clamp(2.0, 1e8) as u32;
    2 * (cycles + cycles % 2)
}

impl Resolved {
    /// Segments this move takes.
    pub fn parts(&self) -> u32 {
        self.parts
    }

    /// Segment `part` (from 0; `parts()` of them).
    pub fn segment(&self, cfg: &MotionConfig, part: u32) -> SegmentTarget {
        let r = &cfg.rates;
        let rot_from = cfg.to_steps(Axis::Rotation, self.from[1]);
        let ins_at = |frac: f64, len: f32| {
            cfg.to_steps(Axis::Insertion, self.from[0] + f64::from(len) * frac)
        };
        // Spin turn `i` goes out one turn on odd-numbered turns and back on even ones.
        let turn_target = |i: u32| {
            if i & 1 == 0 {
                rot_from + i32::from(self.first_dir) * rev_steps(cfg)
            } else {
                rot_from
            }
        };
        let spun_rate = |len: f32| 1.0 / (libm::fabsf(len) / r.insert_mm_s).max(1.0 / r.spin_rev_s);
        match self.mv {
            Move::Rotate { angle_deg } => SegmentTarget {
                target: [
                    ins_at(0.0, 0.0),
                    cfg.to_steps(Axis::Rotation, self.from[1] + f64::from(angle_deg)),
                ],
                rate: r.rotate_deg_s / libm::fabsf(angle_deg),
            },
            Move::Insert { length_mm } => SegmentTarget {
                target: [ins_at(1.0, length_mm), rot_from],
                rate: r.insert_mm_s / libm::fabsf(length_mm),
            },
            Move::InsertSpin { length_mm, .. } => {
                let frac = f64::from(part + 1) / f64::from(self.parts);
                SegmentTarget {
                    target: [ins_at(frac, length_mm), turn_target(part)],
                    rate: spun_rate(length_mm / self.parts as f32),
                }
            }
            Move::InsertDuty { length_mm, duty } => {
                if self.parts == 1 {
                    return SegmentTarget {
                        target: [ins_at(1.0, length_mm), rot_from],
                        rate: r.insert_mm_s / libm::fabsf(length_mm),
                    };
                }
                let cycles = self.parts / 2;
                let (cycle, spun) = (part / 2, part & 1 == 1);
                let held_len = length_mm * duty / cycles as f32;
                let spun_len = length_mm * (1.0 - duty) / cycles as f32;
                if spun {
                    let frac = f64::from(cycle + 1) / f64::from(cycles);
                    SegmentTarget {
                        target: [ins_at(frac, length_mm), turn_target(cycle)],
                        rate: spun_rate(spun_len),
                    }
                } else {
                    // The bevel is held where the last cycle's turn left it.
                    let held = if cycle == 0 {
                        rot_from
                    } else {
                        turn_target(cycle - 1)
                    };
                    let frac = (f64::from(cycle) + f64::from(duty)) / f64::from(cycles);
                    SegmentTarget {
                        target: [ins_at(frac, length_mm), held],
                        rate: r.insert_mm_s / libm::fabsf(held_len),
                    }
                }
            }
        }
    }
}
