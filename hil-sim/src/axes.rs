//! Simulated motors behind the simulated device: the device's motion core steps the simulated
//! axes of `needle_motion::plant` (stage inertia, missed steps, end switches, encoders) as a
//! board's timer would, so motion requests on the link move simulated stages.

use needle_motion::plant::{Plant, PlantAxis, PlantConfig};
use needle_motion::{MotionConfig, MotionError, Rates, SafetyConfig};
use planner_core::device::DeviceService;

/// The simulated stages of the bench driver (`MotionConfig::bench`): motors that follow 20 %
/// past the axes' limits, the stage 5 mm from its home switch, encoders of 4 steps a count.
pub struct SimulatedAxes {
    plant: Plant,
}

impl SimulatedAxes {
    /// Gives `device` the bench axes (the rates and soft limits come with each move request)
    /// and the simulated stages behind them.
    pub fn attach(device: &mut DeviceService) -> Result<SimulatedAxes, MotionError> {
        let rates = Rates {
            insert_mm_s: 2.5,
            rotate_deg_s: 360.0,
            spin_rev_s: 4.0,
        };
        let cfg = MotionConfig::bench(200.0, 360.0, rates);
        device.set_motion(cfg, SafetyConfig::BENCH)?;
        let axis = |i: usize| PlantAxis {
            pull_out: 1.2 * cfg.axes[i].max_speed * cfg.axes[i].steps_per_unit,
            torque_accel: 1.2 * cfg.axes[i].max_accel * cfg.axes[i].steps_per_unit,
            full_step: 16.0,
            encoder_steps: Some(4),
        };
        let plant = Plant::new(PlantConfig {
            axes: [axis(0), axis(1)],
            tick_hz: cfg.tick_hz,
            start: [8000, 0],
            end: 401 * 1600,
        });
        Ok(SimulatedAxes { plant })
    }

    /// The stages (where they are, the steps they missed).
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The stages, to press the e-stop.
    pub fn plant_mut(&mut self) -> &mut Plant {
        &mut self.plant
    }

    /// `ms` of simulated time: the core steps the stages as its timer would (the inputs read
    /// after each step), then the clock runs on to the end of the time at rest.
    pub fn advance(&mut self, device: &mut DeviceService, ms: u32) {
        let Some(core) = device.motion() else { return };
        let end = self.plant.ticks() + u64::from(ms) * u64::from(core.config().tick_hz) / 1000;
        while self.plant.ticks() < end {
            let Some(e) = core.next_step() else { break };
            self.plant.apply(&e);
            core.update(self.plant.now_ms(), &self.plant.inputs());
        }
        if self.plant.ticks() < end {
            let rest = (end - self.plant.ticks()) * 1000 / u64::from(core.config().tick_hz);
            self.plant.wait_ms(u32::try_from(rest).unwrap_or(u32::MAX));
        }
        core.update(self.plant.now_ms(), &self.plant.inputs());
    }
}
