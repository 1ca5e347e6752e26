//! 168 MHz from the PLL, fed by the crystal when it starts, else by the internal oscillator.
//!
//! Every wait is bounded: a board without a crystal, or QEMU (which has no clock tree model),
//! still boots, on the 16 MHz internal oscillator, and says so in the log.

use super::pac;

/// Crystal frequency: 8 MHz on the STM32F4DISCOVERY and most F405/F407 boards. Change it here
/// for a board with another crystal (PLLM divides it down to 1 MHz).
const HSE_MHZ: u8 = 8;
const HSI_MHZ: u8 = 16;
/// Busy-wait iterations before giving up on an oscillator or the PLL (about 10 ms at 16 MHz).
const WAIT_LIMIT: u32 = 40_000;

/// The clocks the board ended up with.
#[derive(Clone, Copy)]
pub struct Clocks {
    /// Core clock (Hz).
    pub sysclk_hz: u32,
    /// APB2 clock, which drives USART1 (Hz).
    #[cfg_attr(feature = "usb", allow(dead_code))]
    pub pclk2_hz: u32,
    /// The clock of APB1's timers (TIM2..TIM5): twice APB1's when APB1 is divided (Hz).
    pub apb1_timer_hz: u32,
    /// The external crystal started.
    pub hse: bool,
    /// The PLL locked and drives the core (else the core runs on the 16 MHz internal oscillator).
    pub pll: bool,
}

fn wait_for(mut ready: impl FnMut() -> bool) -> bool {
    (0..WAIT_LIMIT).any(|_| ready())
}

/// Configures flash wait states, bus prescalers and the PLL (VCO 336 MHz: 168 MHz core, 48 MHz USB).
pub fn init(rcc: &pac::RCC, flash: &pac::FLASH) -> Clocks {
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    let hse = wait_for(|| rcc.cr().read().hserdy().bit_is_set());
    if !hse {
        rcc.cr().modify(|_, w| w.hseon().clear_bit());
        defmt::warn!(
            "no crystal: the PLL runs from the internal oscillator (USB needs the crystal)"
        );
    }
    let input_mhz = if hse { HSE_MHZ } else { HSI_MHZ };
    // SAFETY: register write; the SVD gives these fields no range, and the values are in the
    // ranges RM0090 (6.3.2) allows: PLLM 2..=63, PLLN 50..=432, PLLQ 2..=15.
    rcc.pllcfgr().write(|w| unsafe {
        w.pllsrc().bit(hse);
        w.pllm().bits(input_mhz);
        w.plln().bits(336);
        w.pllp().div2();
        w.pllq().bits(7)
    });
    rcc.cr().modify(|_, w| w.pllon().set_bit());
    if !wait_for(|| rcc.cr().read().pllrdy().bit_is_set()) {
        rcc.cr().modify(|_, w| w.pllon().clear_bit());
        defmt::warn!("the PLL did not lock: running on the 16 MHz internal oscillator");
        return Clocks {
            sysclk_hz: u32::from(HSI_MHZ) * 1_000_000,
            pclk2_hz: u32::from(HSI_MHZ) * 1_000_000,
            apb1_timer_hz: u32::from(HSI_MHZ) * 1_000_000,
            hse,
            pll: false,
        };
    }
    // 5 wait states at 168 MHz and 3.3 V (RM0090 table 10); caches and prefetch on.
    flash.acr().modify(|_, w| {
        w.latency().set(5);
        w.prften().set_bit();
        w.icen().set_bit();
        w.dcen().set_bit()
    });
    // AHB 168 MHz, APB1 42 MHz (max 42), APB2 84 MHz (max 84).
    rcc.cfgr().modify(|_, w| {
        w.hpre().div1();
        w.ppre1().div4();
        w.ppre2().div2();
        w.sw().pll()
    });
    let switched = wait_for(|| rcc.cfgr().read().sws().is_pll());
    // Not switched: the core still runs on the internal oscillator, behind the dividers above
    // (APB1 16/4 MHz, its timers twice that).
    let apb1_timer_hz = if switched { 84_000_000 } else { 8_000_000 };
    Clocks {
        sysclk_hz: 168_000_000,
        pclk2_hz: 84_000_000,
        apb1_timer_hz,
        hse,
        pll: switched,
    }
}
