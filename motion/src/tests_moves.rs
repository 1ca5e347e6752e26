//! The moves' segments: spins and duty cycles as the schedule means them.

use crate::moves::{Planned, Resolved};
use crate::testbench::config;
use crate::{Axis, MotionConfig, MotionError, Move};

fn targets(cfg: &MotionConfig, r: &Resolved) -> Vec<[i32; 2]> {
    (0..r.parts()).map(|p| r.segment(cfg, p).target).collect()
}

#[test]
fn a_spin_alternates_whole_turns_from_the_side_of_zero_twist() {
    let cfg = config();
    let mut at = Planned { at: [10.0, 90.0] };
    let r = at
        .resolve(
            &cfg,
            Move::InsertSpin {
                length_mm: 2.0,
                turns: 4,
            },
        )
        .unwrap();
    // Twisted +90 degrees (800 steps): the first turn goes back through zero.
    let t = targets(&cfg, &r);
    assert_eq!(
        t,
        [[16800, -2400], [17600, 800], [18400, -2400], [19200, 800]]
    );
    assert_eq!(at.at, [12.0, 90.0]);
    let mut zero = Planned { at: [0.0, 0.0] };
    let r = zero
        .resolve(
            &cfg,
            Move::InsertSpin {
                length_mm: 1.0,
                turns: 2,
            },
        )
        .unwrap();
    assert_eq!(targets(&cfg, &r), [[800, 3200], [1600, 0]]);
}

#[test]
fn a_duty_cycled_push_alternates_held_and_spun_shares() {
    let cfg = config();
    let mut at = Planned { at: [0.0, 0.0] };
    // 4 mm at duty 0.75: the spun share (1 mm) takes 1.6 turns at 4 rev/s and 2.5 mm/s: two
    // cycles of a held 1.5 mm and a spun 0.5 mm with one turn, the turns alternating.
    let r = at
        .resolve(
            &cfg,
            Move::InsertDuty {
                length_mm: 4.0,
                duty: 0.75,
            },
        )
        .unwrap();
    let t = targets(&cfg, &r);
    assert_eq!(t, [[2400, 0], [3200, 3200], [5600, 3200], [6400, 0]]);
    let segs: Vec<_> = (0..r.parts()).map(|p| r.segment(&cfg, p)).collect();
    // The held push at the insertion speed, the spun one a turn's time.
    assert_eq!(segs[0].rate, 2.5 / 1.5);
    assert_eq!(segs[1].rate, 4.0);
    // Duty 1 is a plain push; duty 0 spins all the way, an even number of turns.
    let plain = at
        .resolve(
            &cfg,
            Move::InsertDuty {
                length_mm: 1.0,
                duty: 1.0,
            },
        )
        .unwrap();
    assert_eq!(targets(&cfg, &plain), [[8000, 0]]);
    let spun = at
        .resolve(
            &cfg,
            Move::InsertDuty {
                length_mm: 3.0,
                duty: 0.0,
            },
        )
        .unwrap();
    let t = targets(&cfg, &spun);
    assert_eq!(t.len(), 2 * 6);
    assert_eq!(t.last(), Some(&[12800, 0]));
    assert!(t
        .chunks(2)
        .all(|c| c[0][1] == t[0][1] || c[0][1] == 3200 - t[0][1]));
}

#[test]
fn a_failed_move_leaves_the_plan_where_it_was() {
    let cfg = config();
    let mut at = Planned { at: [149.0, 300.0] };
    let e = at.resolve(&cfg, Move::Insert { length_mm: 2.0 });
    assert_eq!(e, Err(MotionError::SoftLimit(Axis::Insertion)));
    // From +300 degrees a spin turns towards zero: -60 is within the limit.
    at.resolve(
        &cfg,
        Move::InsertSpin {
            length_mm: 0.5,
            turns: 2,
        },
    )
    .unwrap();
    let e = at.resolve(&cfg, Move::Rotate { angle_deg: 61.0 });
    assert_eq!(e, Err(MotionError::SoftLimit(Axis::Rotation)));
    assert_eq!(at.at, [149.5, 300.0]);
    let e = at.resolve(
        &cfg,
        Move::Rotate {
            angle_deg: f32::INFINITY,
        },
    );
    assert_eq!(e, Err(MotionError::BadMove));
}

#[test]
fn unusable_settings_are_named() {
    let mut cfg = config();
    cfg.axes[0].max_speed = 1e9;
    assert_eq!(
        cfg.validate(),
        Err(MotionError::Config(crate::ConfigField::MaxSpeed(
            Axis::Insertion
        )))
    );
    let mut cfg = config();
    cfg.axes[1].min = f32::NAN;
    assert_eq!(
        cfg.validate(),
        Err(MotionError::Config(crate::ConfigField::SoftLimits(
            Axis::Rotation
        )))
    );
    let mut cfg = config();
    cfg.rates.spin_rev_s = 0.0;
    assert_eq!(
        cfg.validate(),
        Err(MotionError::Config(crate::ConfigField::Rate))
    );
    let mut cfg = config();
    cfg.tick_hz = 10;
    assert_eq!(
        cfg.validate(),
        Err(MotionError::Config(crate::ConfigField::TickRate))
    );
    let text = MotionError::Config(crate::ConfigField::MaxSpeed(Axis::Insertion)).to_string();
    assert_eq!(text, "unusable motion setting: insertion maximum speed");
}

/// The segments set up ahead by `update` (outside the step interrupt) give the train the
/// interrupt gives when it sets each one up itself, event for event, through a hold and resume.
#[test]
fn segments_set_up_ahead_give_the_same_train_as_set_up_in_the_interrupt() {
    let moves = [
        Move::Rotate { angle_deg: 90.0 },
        Move::InsertSpin {
            length_mm: 3.0,
            turns: 4,
        },
        Move::InsertDuty {
            length_mm: 2.0,
            duty: 0.4,
        },
        Move::Insert { length_mm: 1.5 },
    ];
    let train = |ahead: bool| {
        let mut b = crate::testbench::Bench::homed();
        b.c.execute(&moves).unwrap();
        // The clock stands still: the watchdog never sees a silence.
        let now = b.p.now_ms();
        let mut events = Vec::new();
        loop {
            match b.c.next_step() {
                Some(e) => events.push(e),
                // At rest after the hold: go on.
                None if b.c.state() == crate::State::Holding => b.c.resume().unwrap(),
                None => break,
            }
            if events.len() == 3000 {
                b.c.hold().unwrap();
            }
            b.c.heartbeat();
            if ahead {
                b.c.update(now, &crate::Inputs::default());
            }
        }
        (events, b.c.steps())
    };
    let (ahead, at) = train(true);
    let (inline, at_inline) = train(false);
    assert!(ahead.len() > 10_000, "{}", ahead.len());
    assert_eq!(at, at_inline);
    assert!(ahead == inline, "the trains differ");
}
