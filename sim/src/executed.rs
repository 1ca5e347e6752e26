//! What the driver did of a step the controller broke off: the share of its push, its time and
//! a spin's turns, as the simulated run records it.

use planner_core::execute::schedule::{Op, Step};

/// What the driver did of `step` when it pushed `inserted_mm` of it: all of it, or, broken off,
/// the share of its time that its share of the push took (the push and the spin run at steady
/// rates through the step). A spin broken off finishes the pair of turns it is in: its turns are
/// the even number at or above its share of the step's, so that it leaves the bevel and the twist
/// where they were (as every spin does, and as the simulated world has it), and it lasts as long
/// as those turns take at the step's spin rate when that is longer than its push.
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
            if share < 1.0 && *turns > 0 {
                let planned = *turns;
                let whole = libm::ceilf(planned as f32 * share) as u32;
                *turns = (whole + whole % 2).min(planned);
                let spin_s = step.duration_s * *turns as f32 / planned as f32;
                part.duration_s = (step.duration_s * share).max(spin_s);
            }
            *length_mm = inserted_mm;
        }
    }
    part
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spin(length_mm: f32, turns: u32, duration_s: f32) -> Step {
        Step {
            op: Op::InsertSpin { length_mm, turns },
            duration_s,
        }
    }

    fn turns_of(step: &Step) -> u32 {
        match step.op {
            Op::InsertSpin { turns, .. } => turns,
            _ => panic!("not a spin"),
        }
    }

    #[test]
    fn a_spin_broken_off_finishes_its_pair_of_turns() {
        // 4 mm spun with 6 turns in 1.6 s (2.5 mm/s, 3.75 rev/s), broken off at 2 mm: half the
        // push, 3 of the turns, finished to 4, which take 4/6 of the step's time.
        let part = executed_part(&spin(4.0, 6, 1.6), 2.0);
        assert_eq!(turns_of(&part), 4);
        assert_eq!(part.duration_s, 1.6 * 4.0 / 6.0);
        assert!(matches!(part.op, Op::InsertSpin { length_mm, .. } if length_mm == 2.0));
        // Broken off where the share's turns are already even: the push's time.
        let part = executed_part(&spin(4.0, 8, 1.6), 2.0);
        assert_eq!((turns_of(&part), part.duration_s), (4, 0.8));
    }

    #[test]
    fn every_part_of_a_spin_has_an_even_number_of_turns_within_the_step() {
        let step = spin(10.0, 16, 4.0);
        for k in 0..=100 {
            let inserted = 0.1 * k as f32;
            let part = executed_part(&step, inserted);
            let turns = turns_of(&part);
            assert_eq!(turns % 2, 0, "{inserted} mm: {turns} turns");
            assert!(turns <= 16 && turns as f32 >= 16.0 * inserted / 10.0 - 1e-3);
            assert!(part.duration_s >= 4.0 * inserted / 10.0 - 1e-6);
            assert!(part.duration_s >= 4.0 * turns as f32 / 16.0 - 1e-6);
            assert!(part.duration_s <= 4.0 + 1e-6);
        }
        let whole = executed_part(&step, 10.0);
        assert_eq!((turns_of(&whole), whole.duration_s), (16, 4.0));
    }
}
