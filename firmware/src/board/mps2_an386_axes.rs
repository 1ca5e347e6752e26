//! The QEMU board's axes: the bench driver's motion core (`needle_motion::bench`) stepping
//! simulated stages, with simulated time taken from SysTick, which QEMU runs on the host's
//! clock (at most `MAX_TURN_MS` a loop turn). The stages run in the main loop between polls, so they stand still while the service
//! plans or steers (a real board steps them from a timer interrupt); the step train does not
//! depend on when they run, only how far the clock has gone, so the axes end where the host's
//! simulation of the same moves (`hil-sim --axes`) ends. Each step is a measured region for the
//! instruction-count plugin, and each homing or move one report: the step interrupt's figures
//! in `cargo xtask device-bench`.
//!
//! The e-stop input is the word [`ESTOP_INPUT`]: the emulated board has no pin a test can
//! press, so a test writes the word through QEMU's debugger stub, as a probe would
//! (`needle_devtools::gdb_remote`), and the board reads it every loop turn as it would read the
//! pin (non-zero: pressed).

use crate::axes::Axes;
use crate::marker;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use needle_motion::bench::{bench_config, bench_plant, run_for_with};
use needle_motion::plant::Plant;
use needle_motion::{Controller, SafetyConfig, State};
use planner_core::device::DeviceService;

/// The processor clock of QEMU's MPS2 boards, which SysTick counts.
const SYSCLK_HZ: u32 = 25_000_000;
/// SysTick's full 24-bit range: a loop turn up to 0.67 s long is still timed right.
const RELOAD: u32 = 0x00FF_FFFF;
/// The most simulated time one loop turn runs: an emulator the host left waiting (a loaded
/// machine) slows the simulated world down rather than making it jump, which the link
/// watchdog would take for a silent host.
const MAX_TURN_MS: u32 = 50;

/// The e-stop input as wired: non-zero while pressed. Unmangled, so a debugger finds it by name
/// in the image's symbols; an exported symbol also keeps the compiler from folding the reads
/// of a word nothing in the firmware writes.
#[no_mangle]
pub static ESTOP_INPUT: AtomicU32 = AtomicU32::new(0);

/// Simulated stages and the clock that runs them.
pub struct SimulatedAxes {
    plant: Plant,
    syst: SYST,
    last: u32,
    /// SysTick ticks not yet turned into whole milliseconds.
    ticks: u32,
    /// Steps measured since the axes last came to rest.
    measured: bool,
}

impl SimulatedAxes {
    /// Gives `service` the bench axes and starts the clock; `None` if the set-up is refused
    /// (then the service answers motion requests with `NoMotion`).
    pub fn attach(service: &mut DeviceService, mut syst: SYST) -> Option<SimulatedAxes> {
        let cfg = bench_config();
        service.set_motion(cfg, SafetyConfig::BENCH).ok()?;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_counter();
        Some(SimulatedAxes {
            plant: bench_plant(&cfg),
            last: SYST::get_current(),
            syst,
            ticks: 0,
            measured: false,
        })
    }
}

impl Axes for SimulatedAxes {
    fn advance(&mut self, service: &mut DeviceService) {
        // SysTick counts down and wraps at RELOAD.
        let now = SYST::get_current();
        self.ticks += self.last.wrapping_sub(now) & RELOAD;
        self.last = now;
        // Clears the wrap flag, which nothing else reads.
        let _ = self.syst.has_wrapped();
        let ms = self.ticks / (SYSCLK_HZ / 1000);
        if ms == 0 {
            return;
        }
        self.ticks -= ms * (SYSCLK_HZ / 1000);
        let Some(core) = service.motion() else { return };
        self.plant.estop = ESTOP_INPUT.load(Ordering::Relaxed) != 0;
        run_for_with(core, &mut self.plant, ms.min(MAX_TURN_MS), |c| {
            measured_step(c, &mut self.measured)
        });
        // A homing or a move is over: its steps are one report (the device bench's step figures),
        // sent before any plan can start a region of its own.
        if self.measured && !matches!(core.state(), State::Moving | State::Homing) {
            marker::report();
            self.measured = false;
        }
    }
}

/// One step, as the timer interrupt would take it, a measured region while the axes move; a
/// call that finds them at rest is not measured (it would add to the next plan's count).
fn measured_step(core: &mut Controller, measured: &mut bool) -> Option<needle_motion::StepEvent> {
    if !matches!(core.state(), State::Moving | State::Homing) {
        return core.next_step();
    }
    *measured = true;
    marker::begin();
    let step = core.next_step();
    marker::end();
    step
}
