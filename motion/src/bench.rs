//! The bench driver and its simulated stages, as the simulated device (hil-sim) and the QEMU
//! board both run them: the same set-up and the same stepping, so the host's simulation of a
//! schedule and the emulated board's end on the same step.

use crate::plant::{Plant, PlantAxis, PlantConfig};
use crate::{Controller, MotionConfig, Rates, StepEvent};

/// The bench driver's axes (`MotionConfig::bench` for a 200 mm stage and ±360° of twist); each
/// move request replaces the rates and soft limits with its plan's.
pub fn bench_config() -> MotionConfig {
    let rates = Rates {
        insert_mm_s: 2.5,
        rotate_deg_s: 360.0,
        spin_rev_s: 4.0,
    };
    MotionConfig::bench(200.0, 360.0, rates)
}

/// Simulated stages for `cfg`: the insertion stage 5 mm from its home switch, the far end switch
/// 401 mm out (past any move the soft limits allow).
pub fn bench_plant(cfg: &MotionConfig) -> Plant {
    Plant::new(bench_stages(cfg, 401 * 1600))
}

/// The bench's stages for `cfg` with the far end switch at `end` steps: motors that follow 20 %
/// past the axes' limits, the insertion stage 5 mm (8000 steps) from its home switch, encoders
/// of 4 steps a count.
pub fn bench_stages(cfg: &MotionConfig, end: i32) -> PlantConfig {
    let axis = |i: usize| PlantAxis {
        pull_out: 1.2 * cfg.axes[i].max_speed * cfg.axes[i].steps_per_unit,
        torque_accel: 1.2 * cfg.axes[i].max_accel * cfg.axes[i].steps_per_unit,
        full_step: 16.0,
        encoder_steps: Some(4),
    };
    PlantConfig {
        axes: [axis(0), axis(1)],
        tick_hz: cfg.tick_hz,
        start: [8000, 0],
        end,
    }
}

/// `ms` of simulated time: the core steps the stages as its timer would (the inputs read after
/// each step), then the clock runs on to the end of the time at rest.
pub fn run_for(core: &mut Controller, plant: &mut Plant, ms: u32) {
    run_for_with(core, plant, ms, Controller::next_step);
}

/// `run_for`, each step taken by `next_step` (the timer interrupt's work: a board measures it
/// there).
pub fn run_for_with(
    core: &mut Controller,
    plant: &mut Plant,
    ms: u32,
    mut next_step: impl FnMut(&mut Controller) -> Option<StepEvent>,
) {
    let tick_hz = u64::from(core.config().tick_hz);
    let end = plant.ticks() + u64::from(ms) * tick_hz / 1000;
    while plant.ticks() < end {
        let Some(e) = next_step(core) else { break };
        plant.apply(&e);
        core.update(plant.now_ms(), &plant.inputs());
    }
    if plant.ticks() < end {
        let rest = (end - plant.ticks()) * 1000 / tick_hz;
        plant.wait_ms(u32::try_from(rest).unwrap_or(u32::MAX));
    }
    core.update(plant.now_ms(), &plant.inputs());
}
