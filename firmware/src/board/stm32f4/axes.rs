//! The needle's two stages on STM32F4 pins: the motion core stepped from TIM2's compare
//! interrupt, fed its inputs and clock by a 1 ms control tick while the axes move (and by the
//! main loop at rest), stopped by the e-stop's EXTI interrupt. Pins and timers: `pins`.
//!
//! The core lives here, not in the device service, since the interrupts step it while the
//! service plans; every access (the interrupts', the main loop's and the service's requests,
//! lent through [`MotionPort`]) is one critical section. The step interrupt, the e-stop's and
//! the link's all keep the reset priority, so none preempts another: their frames never stack
//! on each other, only on the main loop's. The cost: a step can wait for a control tick or a
//! request (a segment set up ahead, a move's checks) to finish; the schedule is absolute
//! (`needle_motion::step_clock`), so that step comes late and the train keeps its times.

use super::hw::{self, STEP_IRQ, TICK_IRQ};
use super::pac::interrupt;
use super::pins;
use crate::axes::Axes;
use core::cell::RefCell;
use cortex_m::interrupt::Mutex;
use needle_motion::bench::bench_config;
use needle_motion::step_clock::{
    encoder_steps, prescaler, ticks_for_ns, Action, EncoderCount, Millis, StepClock, TimerError,
    MIN_LEAD,
};
use needle_motion::{Controller, Inputs, MotionError, SafetyConfig, State};
use planner_core::device::{DeviceService, MotionPort};

/// STEP pulse width, and DIR's set-up before a pulse: above what common drivers need (DRV8825:
/// 1.9 µs high and low, 650 ns set-up; TMC2209 and A4988 need less).
const PULSE_NS: u32 = 2_000;
const DIR_SETUP_NS: u32 = 1_000;
/// Events one step interrupt gives at most (catching up after a late start) before it lets
/// the other interrupts in: four pulses and draws, under 60 µs, leave the USART's receive
/// interrupt (a byte every 87 µs at 115200 baud, two held before an overrun) its turn.
const BURST: u32 = 4;

/// Why the axes could not be set up (motion requests are then answered `NoMotion`).
#[derive(Clone, Copy, defmt::Format)]
pub enum SetupError {
    /// The timer clock cannot make the motion core's tick.
    Timer(TimerError),
    /// The motion core refused the driver's settings.
    Motion(MotionError),
}

/// The peripherals the axes own, taken at start-up.
pub struct AxesParts {
    /// TIM2..TIM4's clock (Hz).
    pub timer_hz: u32,
    pub _owned: (
        super::pac::TIM2,
        super::pac::TIM3,
        super::pac::TIM4,
        super::pac::GPIOB,
        super::pac::GPIOC,
        super::pac::EXTI,
        super::pac::SYSCFG,
    ),
}

/// The core and what drives it.
struct Drive {
    core: Controller,
    clock: StepClock,
    millis: Millis,
    encoders: [EncoderCount; 2],
    /// The control tick is running (the axes move); at rest the main loop reads the inputs.
    ticking: bool,
    /// Ticks: the next control tick's count, a millisecond, the pulse width, DIR's set-up.
    next_tick: u32,
    tick_ms: u32,
    pulse: u32,
    dir_setup: u32,
    /// When STEP last went low.
    lowered: u32,
}

/// The drive once set up; a tag, not an `Option`, so that the static is zero bytes (`.bss`).
/// Not boxed: there is no heap.
#[allow(clippy::large_enum_variant)]
#[repr(u8)]
enum Slot {
    Empty,
    Ready(Drive),
}

static DRIVE: Mutex<RefCell<Slot>> = Mutex::new(RefCell::new(Slot::Empty));

/// `f` with the drive, inside a critical section; `None` before set-up.
fn with_drive<R>(f: impl FnOnce(&mut Drive) -> R) -> Option<R> {
    cortex_m::interrupt::free(|cs| match &mut *DRIVE.borrow(cs).try_borrow_mut().ok()? {
        Slot::Ready(d) => Some(f(d)),
        Slot::Empty => None,
    })
}

/// The service's way to the core.
struct Port;

impl MotionPort for Port {
    fn with_motion(&self, f: &mut dyn FnMut(&mut Controller)) {
        with_drive(|d| {
            f(&mut d.core);
            d.settle();
        });
    }
}

static PORT: Port = Port;

/// Sets up the pins, timers and e-stop and gives the service the axes (the bench driver's
/// settings, `needle_motion::bench`).
pub fn attach(service: &mut DeviceService, parts: AxesParts) -> Result<StepperAxes, SetupError> {
    let cfg = bench_config();
    let psc = prescaler(parts.timer_hz, cfg.tick_hz).map_err(SetupError::Timer)?;
    let core = Controller::new(cfg, SafetyConfig::BENCH).map_err(SetupError::Motion)?;
    hw::setup_pins();
    hw::setup_timers(psc);
    hw::setup_estop();
    let now = hw::now();
    let drive = Drive {
        core,
        clock: StepClock::IDLE,
        millis: Millis::new(now),
        encoders: pins::ENCODER_INPUTS.map(|(_, t)| EncoderCount::new(hw::encoder_count(t))),
        ticking: false,
        next_tick: now,
        tick_ms: (cfg.tick_hz / 1000).max(1),
        pulse: ticks_for_ns(PULSE_NS, cfg.tick_hz),
        dir_setup: ticks_for_ns(DIR_SETUP_NS, cfg.tick_hz),
        lowered: now,
    };
    cortex_m::interrupt::free(|cs| {
        if let Ok(mut slot) = DRIVE.borrow(cs).try_borrow_mut() {
            *slot = Slot::Ready(drive);
        }
    });
    service.set_motion_port(&PORT);
    // SAFETY: NVIC register writes. The handlers touch the drive only inside the critical
    // section, and the step clock's and EXTI's registers the axes own.
    unsafe {
        cortex_m::peripheral::NVIC::unmask(super::pac::Interrupt::TIM2);
        cortex_m::peripheral::NVIC::unmask(super::pac::Interrupt::EXTI15_10);
    }
    Ok(StepperAxes)
}

/// The axes as the main loop sees them.
pub struct StepperAxes;

impl Axes for StepperAxes {
    fn advance(&mut self, _service: &mut DeviceService) {
        with_drive(|d| {
            if !d.ticking {
                d.control();
            }
        });
    }
}

impl Drive {
    /// Inputs, clock and watchdog: the core's `update`, then the timers follow its state.
    fn control(&mut self) {
        let now = hw::now();
        let ms = self.millis.at(now, self.core.config().tick_hz);
        let mut encoder = [None; 2];
        for (i, reading) in encoder.iter_mut().enumerate() {
            let (_, timer) = pins::ENCODER_INPUTS[i];
            let counts = self.encoders[i].at(hw::encoder_count(timer));
            *reading = pins::ENCODER_COUNTS_PER_REV[i]
                .and_then(|per_rev| encoder_steps(counts, pins::STEPS_PER_REV, per_rev));
        }
        let inputs = Inputs {
            estop: hw::high(pins::ESTOP),
            limit: hw::high(pins::LIMIT_NEAR) || hw::high(pins::LIMIT_FAR),
            home: hw::high(pins::HOME),
            encoder,
        };
        if let Some(fault) = self.core.update(ms, &inputs) {
            defmt::warn!("motion fault: {}", fault.cause);
        }
        self.settle();
    }

    /// After any change of the core: the drivers' torque, the step train and the control
    /// tick follow its state.
    fn settle(&mut self) {
        let state = self.core.state();
        let moving = matches!(state, State::Moving | State::Homing | State::Holding);
        hw::drivers_enabled(moving || state == State::Armed);
        if !moving {
            self.clock.stop();
            hw::disarm(STEP_IRQ);
            hw::steps_low();
            if self.ticking {
                self.ticking = false;
                hw::disarm(TICK_IRQ);
            }
            return;
        }
        if !self.ticking {
            self.ticking = true;
            self.next_tick = hw::now().wrapping_add(self.tick_ms);
            hw::arm(TICK_IRQ, self.next_tick);
        }
        if !self.clock.is_running() {
            // The step interrupt draws the first step itself: the core's deepest call (a
            // segment set up in `next_step`) then never stacks on the control tick's frames.
            hw::arm(STEP_IRQ, hw::now().wrapping_add(MIN_LEAD));
        }
    }

    /// The step interrupt's work: the events due, then the compare set for the next.
    fn serve(&mut self) {
        if !self.clock.is_running() {
            let Some(first) = self.core.next_step() else {
                return hw::disarm(STEP_IRQ);
            };
            self.clock.start(hw::now(), first);
        }
        for _ in 0..BURST {
            match self.clock.action(hw::now()) {
                Action::Arm(at) => return hw::arm(STEP_IRQ, at),
                Action::Spin(at) => hw::spin_until(at),
                Action::Fire => {
                    if !self.fire() {
                        return;
                    }
                }
            }
        }
        // Still behind after a burst: the rest after the other interrupts had their turn.
        hw::arm(STEP_IRQ, hw::now().wrapping_add(MIN_LEAD));
    }

    /// Gives the pending event's pulses and draws the next; `false` when the train is over.
    fn fire(&mut self) -> bool {
        let Some(e) = self.clock.take() else {
            hw::disarm(STEP_IRQ);
            return false;
        };
        if self.clock.dir_changes(&e) {
            hw::set_dirs(e.step, e.dir);
            hw::spin_until(hw::now().wrapping_add(self.dir_setup));
        }
        // A pulse right after the last (catching up) still gets its time low.
        if hw::now().wrapping_sub(self.lowered) < self.pulse {
            hw::spin_until(self.lowered.wrapping_add(self.pulse));
        }
        hw::steps_high(e.step);
        let raised = hw::now();
        // The next event is drawn while the pulse is high.
        let next = self.core.next_step();
        hw::spin_until(raised.wrapping_add(self.pulse));
        hw::steps_low();
        self.lowered = hw::now();
        match next {
            Some(n) => {
                self.clock.push(n);
                true
            }
            None => {
                self.clock.stop();
                hw::disarm(STEP_IRQ);
                false
            }
        }
    }

    /// The control tick: every millisecond while the axes move, at its own counts.
    fn tick(&mut self) {
        self.control();
        if self.ticking {
            self.next_tick = self.next_tick.wrapping_add(self.tick_ms);
            let now = hw::now();
            // A tick that fell behind (a long critical section) starts again from now.
            if needle_motion::step_clock::reached(now, self.next_tick) {
                self.next_tick = now.wrapping_add(self.tick_ms);
            }
            hw::arm(TICK_IRQ, self.next_tick);
        }
    }
}

#[interrupt]
fn TIM2() {
    let irqs = hw::take_irqs();
    with_drive(|d| {
        if irqs & STEP_IRQ != 0 {
            d.serve();
        }
        if irqs & TICK_IRQ != 0 {
            d.tick();
        }
    });
}

#[interrupt]
fn EXTI15_10() {
    hw::clear_estop();
    // The pulses and the torque stop first, whatever the core is doing.
    hw::steps_low();
    hw::drivers_enabled(false);
    with_drive(|d| {
        d.core.estop();
        d.settle();
    });
}
