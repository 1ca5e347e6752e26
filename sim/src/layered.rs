//! A push through layered tissue: the advance the tip would make in one tissue, turned by the
//! [`Layers`](crate::effects::layers::Layers) into moves (each with its layer's curvature, a
//! stall at a boundary while the robot keeps inserting, the jump when the membrane gives).

use crate::effects::layers::Move;
use crate::reading::Measurement;
use crate::world::{Executed, World};
use crate::MAX_PIECE_MM;
use planner_core::model::kinematics::{Frame, V3};
use planner_core::SegmentKind;
use std::ops::ControlFlow;

impl World {
    /// Pushes the needle `length` (commanded; `true_len` with the advance error) along a
    /// segment of `kind` and `radius` through the layers, in pieces as a plain push: a reading
    /// after every piece of commanded insertion, wherever the tip is.
    pub(crate) fn push_layered(
        &mut self,
        kind: SegmentKind,
        length: f32,
        true_len: f32,
        radius: f32,
        on_measure: &mut impl FnMut(&Measurement, &Frame, V3) -> ControlFlow<()>,
    ) -> Executed {
        let spacing = self.p.measure_every_mm.min(MAX_PIECE_MM);
        let nominal = true_len / libm::ceilf(true_len / spacing).max(1.0);
        self.in_pieces(length, true_len, on_measure, |w, _| {
            let mut moves = std::mem::take(&mut w.moves);
            moves.clear();
            if let Some(l) = w.fx.layers.as_mut() {
                l.advance(w.depth, nominal, &mut moves);
            }
            for m in &moves {
                w.move_tip(kind, m, radius);
            }
            w.moves = moves;
        })
    }

    /// One move of the tip, recorded at most 1 mm apart (a jump too: the tip passes through).
    fn move_tip(&mut self, kind: SegmentKind, m: &Move, radius: f32) {
        let radius = match kind {
            SegmentKind::Arc => radius / m.factor,
            SegmentKind::Line => radius,
        };
        let n = libm::ceilf(m.length / MAX_PIECE_MM).max(1.0) as u32;
        let start = self.tip;
        let mut prev = 0.0;
        for j in 1..=n {
            let t = m.length * j as f32 / n as f32;
            let from = start.advanced(kind, prev, radius);
            self.clearance_along(&from, kind, t - prev, radius);
            self.tip = start.advanced(kind, t, radius);
            self.record(self.tip.p);
            self.depth += t - prev;
            prev = t;
        }
    }
}
