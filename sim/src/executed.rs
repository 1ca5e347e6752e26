//! What the driver did of a step the controller broke off: the share of its push, its time and
//! a spin's turns, as the simulated run records it.

use planner_core::execute::schedule::{Op, Step};

/// What the driver did of `step` when it pushed `inserted_mm` of it: all of it, or, broken off,
/// the share of its time and of a spin's whole turns that its share of the push took (the push
/// and the spin run at steady rates for the whole step).
pub(crate) fn executed_part(step: &Step, inserted_mm: f32) -> Step {
    let share = |planned_mm: f32| {
        if inserted_mm < planned_mm && planned_mm > 0.0 {
            inserted_mm / planned_mm
        } else {
            1.0
        }
    };
    let mut part = *step;
    match &mut part.op {
        Op::Rotate { .. } => {}
        Op::Insert { length_mm } | Op::InsertDuty { length_mm, .. } => {
            let share = share(*length_mm);
            if share < 1.0 {
                part.duration_s *= share;
            }
            *length_mm = inserted_mm;
        }
        Op::InsertSpin { length_mm, turns } => {
            let share = share(*length_mm);
            if share < 1.0 {
                part.duration_s *= share;
                *turns = (*turns as f32 * share) as u32;
            }
            *length_mm = inserted_mm;
        }
    }
    part
}
