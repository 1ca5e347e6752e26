//! The axes' registers: GPIOB/GPIOC, TIM2..TIM4, EXTI and SYSCFG, at the addresses of the pin
//! table (`pins`). The only `unsafe` of the axes is the volatile access in `read` and `write`.
//! The axes own these peripherals: their PAC singletons are moved into `AxesParts` at start-up
//! and nothing else touches them. Read-modify-writes happen during set-up (interrupts not yet
//! unmasked) or inside the axes' critical section; BSRR and the timers' status and EXTI's
//! pending register are written whole, where a write changes only the bits set in it.

use super::pins::{self, Pin, ENCODER_INPUTS, TIM2};
use core::ptr::{read_volatile, write_volatile};
use needle_motion::step_clock::reached;

// GPIO registers (RM0090 8.4).
const MODER: usize = 0x00;
const PUPDR: usize = 0x0C;
const IDR: usize = 0x10;
const BSRR: usize = 0x18;
const AFRL: usize = 0x20;
// Timer registers (RM0090 18.4).
const CR1: usize = 0x00;
const SMCR: usize = 0x08;
const DIER: usize = 0x0C;
const SR: usize = 0x10;
const EGR: usize = 0x14;
const CCMR1: usize = 0x18;
const CNT: usize = 0x24;
const PSC: usize = 0x28;
const ARR: usize = 0x2C;
const CCR1: usize = 0x34;
const CCR2: usize = 0x38;
const CEN: u32 = 1;
const UG: u32 = 1;
/// CC1 (the step) and CC2 (the control tick): their bit in DIER and in SR alike.
pub const STEP_IRQ: u32 = 1 << 1;
pub const TICK_IRQ: u32 = 1 << 2;
// EXTI and SYSCFG registers (RM0090 12.3, 9.2).
const EXTI_IMR: usize = 0x00;
const EXTI_RTSR: usize = 0x08;
const EXTI_PR: usize = 0x14;
const SYSCFG_EXTICR1: usize = 0x08;
/// Busy-wait iterations before giving up on a count (a stopped counter): far more than the
/// few ticks any wait here is for.
const SPIN_LIMIT: u32 = 100_000;

fn read(addr: usize) -> u32 {
    // SAFETY: `addr` is a 32-bit register of a peripheral the axes own (see the module's
    // comment), always mapped; a volatile read has no effect beyond the device's own.
    unsafe { read_volatile(addr as *const u32) }
}

fn write(addr: usize, value: u32) {
    // SAFETY: as in `read`; only the axes write these registers, and never concurrently with
    // a read-modify-write of the same one (see the module's comment).
    unsafe { write_volatile(addr as *mut u32, value) }
}

fn modify(addr: usize, f: impl FnOnce(u32) -> u32) {
    write(addr, f(read(addr)));
}

/// Sets a pin's 2-bit field (`MODER`, `PUPDR`) to `value`.
fn field2(pin: Pin, reg: usize, value: u32) {
    let shift = 2 * u32::from(pin.n);
    modify(pin.base() + reg, |v| {
        (v & !(0b11 << shift)) | (value << shift)
    });
}

/// Drives a pin high or low (BSRR: the upper half resets).
fn drive(pin: Pin, high: bool) {
    let bit = if high { pin.mask() } else { pin.mask() << 16 };
    write(pin.base() + BSRR, bit);
}

/// Outputs at rest (drivers disabled, no pulse), inputs pulled up, encoder pins on their timers.
pub fn setup_pins() {
    drive(pins::DRIVERS_EN, true);
    for pin in pins::STEP.iter().chain(&pins::DIR) {
        drive(*pin, false);
    }
    for pin in pins::STEP
        .iter()
        .chain(&pins::DIR)
        .chain([&pins::DRIVERS_EN])
    {
        field2(*pin, MODER, 0b01);
    }
    for pin in pins::INPUTS {
        field2(pin, PUPDR, 0b01);
    }
    for (ab, _) in ENCODER_INPUTS {
        for pin in ab {
            // The encoder pins are all below 8: AFRL holds them.
            let shift = 4 * u32::from(pin.n & 7);
            modify(pin.base() + AFRL, |v| {
                (v & !(0xF << shift)) | (pins::AF_ENCODER << shift)
            });
            field2(pin, PUPDR, 0b01);
            field2(pin, MODER, 0b10);
        }
    }
}

/// TIM2 free-running over its 32 bits at the timer clock divided by `psc + 1`, no interrupt;
/// the encoder timers counting both edges of both channels (encoder mode 3).
pub fn setup_timers(psc: u16) {
    write(TIM2 + PSC, u32::from(psc));
    write(TIM2 + ARR, u32::MAX);
    // The prescaler only takes a new value at an update event: make one, then clear its flag.
    write(TIM2 + EGR, UG);
    write(TIM2 + SR, 0);
    write(TIM2 + CR1, CEN);
    for (_, timer) in ENCODER_INPUTS {
        write(timer + ARR, 0xFFFF);
        // CC1S = CC2S = 01 (TI1, TI2 as inputs), each filtered over 8 samples (IC1F = IC2F = 3).
        write(timer + CCMR1, 0x3131);
        write(timer + SMCR, 0b011);
        write(timer + CR1, CEN);
    }
}

/// The e-stop pin on EXTI, interrupting on its rising edge (the contact opening).
pub fn setup_estop() {
    let line = u32::from(pins::ESTOP.n);
    let cr = SYSCFG_EXTICR1 + 4 * (line as usize / 4);
    let shift = 4 * (line % 4);
    modify(pins::SYSCFG + cr, |v| {
        (v & !(0xF << shift)) | ((pins::ESTOP.port as u32) << shift)
    });
    modify(pins::EXTI + EXTI_RTSR, |v| v | 1 << line);
    write(pins::EXTI + EXTI_PR, 1 << line);
    modify(pins::EXTI + EXTI_IMR, |v| v | 1 << line);
}

/// Clears the e-stop's pending interrupt.
pub fn clear_estop() {
    write(pins::EXTI + EXTI_PR, 1 << pins::ESTOP.n);
}

/// The step clock's count.
pub fn now() -> u32 {
    read(TIM2 + CNT)
}

/// Waits until the step clock reaches `target` (a few ticks at most).
pub fn spin_until(target: u32) {
    for _ in 0..SPIN_LIMIT {
        if reached(now(), target) {
            return;
        }
    }
}

/// Interrupts at count `at` with `irq` (`STEP_IRQ` on CC1, `TICK_IRQ` on CC2).
pub fn arm(irq: u32, at: u32) {
    write(TIM2 + if irq == STEP_IRQ { CCR1 } else { CCR2 }, at);
    // A flag left from an earlier match (compares match whether enabled or not) would fire now.
    write(TIM2 + SR, !irq);
    modify(TIM2 + DIER, |v| v | irq);
}

/// No more interrupts from `irq`.
pub fn disarm(irq: u32) {
    modify(TIM2 + DIER, |v| v & !irq);
}

/// The enabled compare interrupts that are pending, now cleared.
pub fn take_irqs() -> u32 {
    let pending = read(TIM2 + SR) & read(TIM2 + DIER) & (STEP_IRQ | TICK_IRQ);
    write(TIM2 + SR, !pending);
    pending
}

/// Sets the DIR output of the axes in `axes` to `dir` (+1 forward, high).
pub fn set_dirs(axes: [bool; 2], dir: [i8; 2]) {
    for ((on, pin), d) in axes.into_iter().zip(pins::DIR).zip(dir) {
        if on {
            drive(pin, d > 0);
        }
    }
}

/// Raises STEP on the axes in `axes`.
pub fn steps_high(axes: [bool; 2]) {
    for (on, pin) in axes.into_iter().zip(pins::STEP) {
        if on {
            drive(pin, true);
        }
    }
}

/// Lowers both STEP outputs.
pub fn steps_low() {
    for pin in pins::STEP {
        drive(pin, false);
    }
}

/// Gives or takes the motors' torque (EN is active low).
pub fn drivers_enabled(on: bool) {
    drive(pins::DRIVERS_EN, !on);
}

/// Whether an input reads high (a closed switch, a pressed e-stop).
pub fn high(pin: Pin) -> bool {
    read(pin.base() + IDR) & pin.mask() != 0
}

/// An encoder timer's 16-bit count.
pub fn encoder_count(timer: usize) -> u16 {
    read(timer + CNT) as u16
}
