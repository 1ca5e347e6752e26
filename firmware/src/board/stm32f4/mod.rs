//! STM32F405/F407 at 168 MHz: the link on USART1 (PA9 TX, PA10 RX, 115200 8N1) or, with the
//! `usb` feature, on a USB CDC-ACM port (PA11/PA12); an independent watchdog; logs over RTT; the
//! needle's two stages on step/dir outputs, switch inputs and an e-stop interrupt (`axes`, with
//! every pin and timer in `pins`).
//!
//! Also boots in QEMU's `netduinoplus2` (an STM32F405 without a clock tree model): clock bring-up
//! waits are bounded and fall back to the 16 MHz internal oscillator.

mod axes;
mod clocks;
mod hw;
mod pins;
#[cfg(not(feature = "usb"))]
mod usart;
#[cfg(feature = "usb")]
mod usb;
mod watchdog;

use stm32f4::stm32f405 as pac;

/// Board name, as `cargo xtask device-bench` reports it.
pub const NAME: &str = "stm32f4";

/// The board's link: USART1, or the USB port with the `usb` feature.
#[cfg(not(feature = "usb"))]
pub type BoardLink = usart::Usart1;
/// The board's link: USART1, or the USB port with the `usb` feature.
#[cfg(feature = "usb")]
pub type BoardLink = usb::UsbSerial;

pub use axes::AxesParts;

/// Brings up clocks, watchdog and link, and hands out what the axes take.
pub fn init() -> (BoardLink, AxesParts) {
    let Some(dp) = pac::Peripherals::take() else {
        // `init` runs once, from `main`; a second call is a bug that a reset clears.
        fatal_stop()
    };
    if dp.RCC.csr().read().wdgrstf().bit_is_set() {
        defmt::warn!("the previous run was reset by the watchdog");
    }
    dp.RCC.csr().modify(|_, w| w.rmvf().set_bit());
    let clocks = clocks::init(&dp.RCC, &dp.FLASH);
    defmt::info!(
        "sysclk {=u32} Hz (crystal: {=bool}, PLL: {=bool})",
        clocks.sysclk_hz,
        clocks.hse,
        clocks.pll
    );
    let watchdog = watchdog::start(dp.IWDG);
    dp.RCC.ahb1enr().modify(|_, w| {
        w.gpioben().set_bit();
        w.gpiocen().set_bit()
    });
    dp.RCC.apb1enr().modify(|_, w| {
        w.tim2en().set_bit();
        w.tim3en().set_bit();
        w.tim4en().set_bit()
    });
    dp.RCC.apb2enr().modify(|_, w| w.syscfgen().set_bit());
    let parts = AxesParts {
        timer_hz: clocks.apb1_timer_hz,
        _owned: (
            dp.TIM2, dp.TIM3, dp.TIM4, dp.GPIOB, dp.GPIOC, dp.EXTI, dp.SYSCFG,
        ),
    };
    #[cfg(not(feature = "usb"))]
    let link = usart::Usart1::init(dp.USART1, &dp.RCC, &dp.GPIOA, clocks, watchdog);
    #[cfg(feature = "usb")]
    let link = usb::UsbSerial::init(
        dp.OTG_FS_GLOBAL,
        dp.OTG_FS_DEVICE,
        dp.OTG_FS_PWRCLK,
        &dp.RCC,
        &dp.GPIOA,
        clocks,
        watchdog,
    );
    (link, parts)
}

/// The needle's stages (`None`, and motion requests answered `NoMotion`, if their set-up
/// failed: the reason is logged).
pub fn axes(
    service: &mut planner_core::device::DeviceService,
    parts: AxesParts,
) -> Option<axes::StepperAxes> {
    match axes::attach(service, parts) {
        Ok(a) => Some(a),
        Err(e) => {
            defmt::error!("no axes: {}", e);
            None
        }
    }
}

/// The link for the panic handler's last words.
#[cfg(not(feature = "usb"))]
pub fn panic_link() -> usart::PanicUsart {
    usart::PanicUsart::steal()
}

/// The link for the panic handler's last words: none over USB (the bus needs the main loop).
#[cfg(feature = "usb")]
pub fn panic_link() -> usb::NoLink {
    usb::NoLink
}

/// Resets the chip: a fault on the bench should leave a board that answers again.
pub fn fatal_stop() -> ! {
    cortex_m::peripheral::SCB::sys_reset()
}
