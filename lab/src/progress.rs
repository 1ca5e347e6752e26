//! Whether the robot's reported progress could come from what it was commanded: its depth never
//! goes back, never passes the end of the step list, and grows by at most one piece at a time;
//! its base roll stays within the list's rotations of where the list began.

use planner_core::execute::schedule::{Op, Step};

/// The most a piece may advance the commanded depth (mm). Pieces are at most 1 mm of true
/// insertion; a push whose true length falls short of the commanded one spreads the commanded
/// length over fewer pieces, so a piece's commanded share may pass 1 mm, but not 2 mm unless the
/// needle went less than half as far as commanded.
pub const MAX_PIECE_ADVANCE_MM: f32 = 2.0;

/// Rounding allowed on the sums of pieces (mm, degrees).
const ROUNDING: f32 = 1e-2;

/// What the robot was commanded, since the current step list was sent.
#[derive(Clone, Copy, Debug, Default)]
pub struct Commanded {
    depth_mm: f32,
    base_deg: f32,
    list_start_depth_mm: f32,
    list_start_base_deg: f32,
    insert_mm: f32,
    rotate_deg: f32,
}

impl Commanded {
    /// A new step list goes out from the progress last reported.
    pub fn list_sent(&mut self, steps: &[Step]) {
        self.list_start_depth_mm = self.depth_mm;
        self.list_start_base_deg = self.base_deg;
        self.insert_mm = steps.iter().map(|s| s.op.inserted_mm()).sum();
        self.rotate_deg = steps
            .iter()
            .map(|s| match s.op {
                Op::Rotate { angle_deg } => angle_deg.abs(),
                _ => 0.0,
            })
            .sum();
    }

    /// Takes a reported progress; says why it cannot be true, if it cannot.
    pub fn check(&mut self, depth_mm: f32, base_deg: f32) -> Result<(), String> {
        let end = self.list_start_depth_mm + self.insert_mm;
        if depth_mm < self.depth_mm - ROUNDING {
            return Err(format!(
                "depth went back from {} to {depth_mm} mm",
                self.depth_mm
            ));
        }
        if depth_mm > end + ROUNDING {
            return Err(format!(
                "depth {depth_mm} mm is past the commanded {end} mm"
            ));
        }
        if depth_mm - self.depth_mm > MAX_PIECE_ADVANCE_MM {
            return Err(format!(
                "depth jumped from {} to {depth_mm} mm in one piece",
                self.depth_mm
            ));
        }
        let turned = (base_deg - self.list_start_base_deg).abs();
        if turned > self.rotate_deg + ROUNDING {
            return Err(format!(
                "base roll {base_deg} deg is {turned} deg from the list's start, which turns {} deg",
                self.rotate_deg
            ));
        }
        self.depth_mm = depth_mm;
        self.base_deg = base_deg;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(op: Op) -> Step {
        Step {
            op,
            duration_s: 1.0,
        }
    }

    #[test]
    fn progress_along_the_commands_passes_and_anything_else_is_caught() {
        let mut c = Commanded::default();
        c.list_sent(&[
            step(Op::Insert { length_mm: 3.0 }),
            step(Op::Rotate { angle_deg: -90.0 }),
            step(Op::Insert { length_mm: 1.5 }),
        ]);
        for (d, b) in [
            (1.0, 0.0),
            (2.0, 0.0),
            (3.0, 0.0),
            (3.0, -90.0),
            (4.5, -90.0),
        ] {
            assert_eq!(c.check(d, b), Ok(()), "{d} {b}");
        }
        assert!(c.check(4.0, -90.0).unwrap_err().contains("back"));
        assert!(c.check(5.0, -90.0).unwrap_err().contains("past"));
        c.list_sent(&[step(Op::Insert { length_mm: 10.0 })]);
        assert!(c.check(7.0, -90.0).unwrap_err().contains("jumped"));
        assert!(c.check(5.5, 0.0).unwrap_err().contains("base roll"));
        assert_eq!(c.check(5.5, -90.0), Ok(()));
    }
}
