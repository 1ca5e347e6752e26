//! A push in pieces: the tracker reads after every piece of insertion (at most its spacing and
//! 1 mm long), and the controller may break the push off between pieces. One loop for the plain
//! and the layered world; what moves the tip through a piece is theirs.

use crate::reading::Measurement;
use crate::world::{Executed, World};
use crate::MAX_PIECE_MM;
use planner_core::model::kinematics::{Frame, V3};
use std::ops::ControlFlow;

impl World {
    /// A push of `length` (commanded; `true_len` as the tissue takes it) in pieces of at most
    /// the tracker's spacing: `advance(world, share)` moves the tip through the piece that ends
    /// at `share` of the push, then the robot's count follows and the tracker reads; the
    /// controller may break off after any piece but the last.
    pub(crate) fn in_pieces(
        &mut self,
        length: f32,
        true_len: f32,
        on_measure: &mut impl FnMut(&Measurement, &Frame, V3) -> ControlFlow<()>,
        mut advance: impl FnMut(&mut World, f32),
    ) -> Executed {
        let spacing = self.p.measure_every_mm.min(MAX_PIECE_MM);
        let pieces = libm::ceilf(true_len / spacing).max(1.0) as u32;
        let mut commanded = 0.0;
        for k in 1..=pieces {
            let share = k as f32 / pieces as f32;
            advance(self, share);
            self.commanded += length * share - commanded;
            commanded = length * share;
            self.moved();
            let m = self.measure();
            if on_measure(&m, &self.tip, self.true_target).is_break() && k < pieces {
                return Executed {
                    inserted_mm: commanded,
                    interrupted: true,
                };
            }
        }
        Executed {
            inserted_mm: length,
            interrupted: false,
        }
    }
}
