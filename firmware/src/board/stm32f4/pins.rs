//! Every pin and timer the axes use, in one table (STM32F405/F407, LQFP64 and up).
//!
//! The link keeps GPIOA (USART1 on PA9/PA10, USB on PA11/PA12, SWD on PA13/PA14); the axes use
//! GPIOB and GPIOC only. Switches and the e-stop are wired normally closed to ground with the
//! pin's pull-up: a pressed switch, an unplugged connector and a cut wire all read high, as
//! "closed" to the motion core, so a broken wire stops the axes rather than hiding a switch.

/// A GPIO port, by its index in the AHB1 map (0x4002_0000 + 0x400 per port).
#[derive(Clone, Copy)]
pub enum Port {
    B = 1,
    C = 2,
}

/// One pin.
#[derive(Clone, Copy)]
pub struct Pin {
    pub port: Port,
    pub n: u8,
}

impl Pin {
    const fn new(port: Port, n: u8) -> Pin {
        Pin { port, n }
    }

    /// The pin's bit in its port's IDR, and in the lower (set) half of BSRR.
    pub const fn mask(self) -> u32 {
        1 << self.n
    }

    /// Its port's register block.
    pub const fn base(self) -> usize {
        GPIO_BASE + 0x400 * self.port as usize
    }
}

const GPIO_BASE: usize = 0x4002_0000;

// Outputs, push-pull. PC6..PC9 are also TIM8's four channels (AF3), should a board ever give
// the pulses to a timer's outputs instead of the step interrupt.
/// Insertion driver STEP: a pulse per microstep, rising edge.
pub const INSERT_STEP: Pin = Pin::new(Port::C, 6);
/// Insertion driver DIR: high steps forward (insertion deeper).
pub const INSERT_DIR: Pin = Pin::new(Port::C, 7);
/// Rotation driver STEP.
pub const ROTATE_STEP: Pin = Pin::new(Port::C, 8);
/// Rotation driver DIR: high steps forward (positive twist).
pub const ROTATE_DIR: Pin = Pin::new(Port::C, 9);
/// Both drivers' EN, active low: high (torque off) until armed, and again when disarmed or
/// faulted, so an e-stop also cuts the motors' torque.
pub const DRIVERS_EN: Pin = Pin::new(Port::C, 10);

/// STEP and DIR of each axis, in `Axis` order.
pub const STEP: [Pin; 2] = [INSERT_STEP, ROTATE_STEP];
pub const DIR: [Pin; 2] = [INSERT_DIR, ROTATE_DIR];

// Inputs, pulled up, normally closed to ground (high = closed switch, pressed e-stop).
/// Home switch of the insertion stage, at its retracted end.
pub const HOME: Pin = Pin::new(Port::B, 0);
/// Hard limit behind the home switch (the stage overran it).
pub const LIMIT_NEAR: Pin = Pin::new(Port::B, 1);
/// Hard limit at the insertion stage's far end.
pub const LIMIT_FAR: Pin = Pin::new(Port::B, 10);
/// E-stop, also on EXTI line 12 (interrupt `EXTI15_10`, rising edge: the contact opens).
pub const ESTOP: Pin = Pin::new(Port::B, 12);

/// Every input with a pull-up.
pub const INPUTS: [Pin; 4] = [HOME, LIMIT_NEAR, LIMIT_FAR, ESTOP];

// Quadrature encoders, channel A on CH1 and B on CH2 of a 16-bit timer in encoder mode (AF2).
// PB4 is JTAG's NJTRST, free when the board is debugged over SWD.
/// Insertion encoder A/B: TIM3_CH1/CH2.
pub const INSERT_ENCODER: [Pin; 2] = [Pin::new(Port::B, 4), Pin::new(Port::B, 5)];
/// Rotation encoder A/B: TIM4_CH1/CH2.
pub const ROTATE_ENCODER: [Pin; 2] = [Pin::new(Port::B, 6), Pin::new(Port::B, 7)];
/// The encoder pins' alternate function (TIM3..TIM5).
pub const AF_ENCODER: u32 = 2;

/// Each axis' encoder input, in `Axis` order: its A/B pins and its timer. Both are set up
/// whether an encoder is fitted or not (an open input counts nothing).
pub const ENCODER_INPUTS: [([Pin; 2], usize); 2] = [(INSERT_ENCODER, TIM3), (ROTATE_ENCODER, TIM4)];

/// The bench driver's microsteps a motor turn (200 full steps × 16).
pub const STEPS_PER_REV: u32 = 3200;

/// Each axis' encoder counts a motor turn (4 per line in quadrature), `None` where none is
/// fitted, in `Axis` order. None on the bench driver: an encoder declared here but not
/// connected would read still while its motor turns, a following-error fault on the first
/// move. A 1000-line encoder on the insertion motor would be `[Some(4000), None]`.
pub const ENCODER_COUNTS_PER_REV: [Option<u32>; 2] = [None, None];

// Timers (register blocks). APB1 timers run at twice APB1's clock when it is divided: 84 MHz
// behind the PLL, 16 MHz on the internal oscillator (`Clocks::apb1_timer_hz`).
/// The step clock: TIM2, 32 bits, free-running at the motion core's tick rate. CC1's compare
/// interrupt gives each step at its count; CC2's is the control tick (inputs, clock, watchdog,
/// set-ups ahead) every millisecond while the axes move. No pin.
pub const TIM2: usize = 0x4000_0000;
/// Insertion encoder (16 bits).
pub const TIM3: usize = 0x4000_0400;
/// Rotation encoder (16 bits).
pub const TIM4: usize = 0x4000_0800;

/// EXTI's and SYSCFG's register blocks (the e-stop's interrupt).
pub const EXTI: usize = 0x4001_3C00;
pub const SYSCFG: usize = 0x4001_3800;
