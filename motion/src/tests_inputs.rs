//! Any input, however wrong, is refused with a reason or executed within the limits: seeded
//! random settings and moves, far outside what a schedule holds, never panic.

use crate::check::TrainCheck;
use crate::testbench::config;
use crate::{Controller, Inputs, MotionConfig, Move, SafetyConfig, State};

/// SplitMix64: a seeded stream without a dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number of any size and sign, or a special value.
    fn wild(&mut self) -> f32 {
        match self.next() % 8 {
            0 => f32::NAN,
            1 => f32::INFINITY,
            2 => -0.0,
            3 => f32::from_bits(self.next() as u32),
            _ => (self.next() % 20_000) as f32 / 100.0 - 50.0,
        }
    }

    fn mv(&mut self) -> Move {
        match self.next() % 4 {
            0 => Move::Rotate {
                angle_deg: self.wild() * 10.0,
            },
            1 => Move::Insert {
                length_mm: self.wild(),
            },
            2 => Move::InsertSpin {
                length_mm: self.wild(),
                turns: (self.next() % 6) as u32,
            },
            _ => Move::InsertDuty {
                length_mm: self.wild(),
                duty: self.wild() / 50.0,
            },
        }
    }
}

fn wild_config(rng: &mut Rng) -> MotionConfig {
    let mut cfg = config();
    for _ in 0..(rng.next() % 3) {
        match rng.next() % 6 {
            0 => cfg.axes[(rng.next() % 2) as usize].steps_per_unit = rng.wild().abs(),
            1 => cfg.axes[(rng.next() % 2) as usize].max_accel = rng.wild().abs(),
            2 => cfg.axes[(rng.next() % 2) as usize].max = rng.wild(),
            3 => cfg.rates.spin_rev_s = rng.wild(),
            4 => cfg.tick_hz = (rng.next() % 3_000_000) as u32,
            _ => cfg.homing_travel_mm = rng.wild(),
        }
    }
    cfg
}

#[test]
fn wild_settings_and_moves_are_refused_or_run_within_the_limits() {
    let mut rng = Rng(7);
    let (mut refused, mut ran) = (0, 0);
    for _ in 0..3000 {
        let cfg = wild_config(&mut rng);
        let Ok(mut c) = Controller::new(cfg, SafetyConfig::BENCH) else {
            refused += 1;
            continue;
        };
        c.arm().unwrap();
        c.home().unwrap();
        c.update(
            0,
            &Inputs {
                home: true,
                ..Inputs::default()
            },
        );
        while c.next_step().is_some() {}
        let moves: Vec<Move> = (0..rng.next() % 5).map(|_| rng.mv()).collect();
        if c.execute(&moves).is_err() {
            refused += 1;
            assert_eq!((c.state(), c.steps()), (State::Armed, [0, 0]));
            continue;
        }
        let mut check = TrainCheck::new(cfg, [0, 0]);
        for _ in 0..200_000 {
            let Some(e) = c.next_step() else { break };
            check.push(&e).unwrap();
            c.heartbeat();
        }
        ran += 1;
    }
    assert!(refused > 100 && ran > 100, "{refused} refused, {ran} ran");
}
