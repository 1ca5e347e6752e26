//! A controller wired to a simulated plant, for the tests.

use crate::plant::{Plant, PlantConfig};
use crate::{Controller, MotionConfig, Rates, SafetyConfig, State};

pub const RATES: Rates = Rates {
    insert_mm_s: 2.5,
    rotate_deg_s: 360.0,
    spin_rev_s: 4.0,
};

pub fn config() -> MotionConfig {
    MotionConfig::bench(150.0, 360.0, RATES)
}

/// The bench's plant (`bench::bench_stages`), the far switch 1 mm past the needle's length.
pub fn plant_config(cfg: &MotionConfig) -> PlantConfig {
    crate::bench::bench_stages(cfg, 151 * 1600)
}

pub struct Bench {
    pub c: Controller,
    pub p: Plant,
    /// Whether the host's heartbeat arrives with every event.
    pub host: bool,
}

impl Bench {
    pub fn new() -> Bench {
        let cfg = config();
        Bench::with(cfg, plant_config(&cfg))
    }

    pub fn with(cfg: MotionConfig, plant: PlantConfig) -> Bench {
        Bench {
            c: Controller::new(cfg, SafetyConfig::BENCH).unwrap(),
            p: Plant::new(plant),
            host: true,
        }
    }

    /// Up to `n` events through the plant, the inputs read after each; how many there were.
    pub fn drive(&mut self, n: usize) -> usize {
        for k in 0..n {
            let Some(e) = self.c.next_step() else {
                return k;
            };
            self.p.apply(&e);
            if self.host {
                self.c.heartbeat();
            }
            let inputs = self.p.inputs();
            self.c.update(self.p.now_ms(), &inputs);
        }
        n
    }

    /// Armed and homed at the switch.
    pub fn homed() -> Bench {
        let mut b = Bench::new();
        b.c.arm().unwrap();
        b.c.home().unwrap();
        b.drive(usize::MAX);
        assert_eq!(b.c.state(), State::Armed);
        // The stage settles.
        b.p.wait_ms(100);
        b
    }
}
