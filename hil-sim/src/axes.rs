//! Simulated motors behind the simulated device: the device's motion core steps the simulated
//! axes of `needle_motion::plant` (stage inertia, missed steps, end switches, encoders) as a
//! board's timer would, so motion requests on the link move simulated stages. The set-up and the
//! stepping are `needle_motion::bench`'s, the QEMU board's too.

use needle_motion::bench::{bench_config, bench_plant, run_for};
use needle_motion::plant::Plant;
use needle_motion::{MotionError, SafetyConfig};
use planner_core::device::DeviceService;

/// The simulated stages of the bench driver (`needle_motion::bench`).
pub struct SimulatedAxes {
    plant: Plant,
}

impl SimulatedAxes {
    /// Gives `device` the bench axes (the rates and soft limits come with each move request)
    /// and the simulated stages behind them.
    pub fn attach(device: &mut DeviceService) -> Result<SimulatedAxes, MotionError> {
        let cfg = bench_config();
        device.set_motion(cfg, SafetyConfig::BENCH)?;
        Ok(SimulatedAxes {
            plant: bench_plant(&cfg),
        })
    }

    /// The stages (where they are, the steps they missed).
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The stages, to press the e-stop.
    pub fn plant_mut(&mut self) -> &mut Plant {
        &mut self.plant
    }

    /// `ms` of simulated time (`needle_motion::bench::run_for`).
    pub fn advance(&mut self, device: &mut DeviceService, ms: u32) {
        if let Some(core) = device.motion() {
            run_for(core, &mut self.plant, ms);
        }
    }
}
