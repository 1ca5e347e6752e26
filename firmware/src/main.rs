//! needle-planner firmware: the planner-core device service behind a serial link.
//!
//! The board code only moves bytes and counts work: every received byte goes to
//! [`DeviceService::receive`], and [`pump`] calls [`DeviceService::poll`] (one bounded unit of
//! work: decode a frame, or plan one form) and sends what it produces. The service, the planner and
//! the wire protocol are the same code the host runs.
//!
//! Boards are cargo features, exactly one at a time: `mps2-an386` (QEMU), `stm32f4` (STM32F405/407,
//! USART1) and `usb` (stm32f4 with a USB CDC-ACM port instead of the USART).
#![no_std]
#![no_main]

#[cfg(all(feature = "mps2-an386", feature = "stm32f4"))]
compile_error!("choose one board feature: `mps2-an386` or `stm32f4` (or `usb`), not both");
#[cfg(not(any(feature = "mps2-an386", feature = "stm32f4")))]
compile_error!(
    "choose a board feature: `--features mps2-an386`, `--features stm32f4` or `--features usb`"
);

mod axes;
mod board;
mod link;
mod marker;
mod panic;
mod pump;

use cortex_m_rt::entry;
use planner_core::device::{DeviceIdentity, DeviceService};

/// How the firmware introduces itself in the protocol's hello.
const IDENTITY: DeviceIdentity = DeviceIdentity {
    name: board::NAME,
    firmware: env!("CARGO_PKG_VERSION"),
    build: env!("NEEDLE_FIRMWARE_BUILD"),
};

// The global defmt logger: semihosting under QEMU (decoded with `defmt-print -e ELF` from QEMU's
// stdout), RTT on a board (read by probe-rs).
#[cfg(feature = "stm32f4")]
use defmt_rtt as _;
#[cfg(feature = "mps2-an386")]
use defmt_semihosting as _;

// Keep the critical-section implementation of cortex-m linked in (defmt's loggers use it).
use cortex_m as _;

#[entry]
fn main() -> ! {
    // cortex-m-rt turns these into `&'static mut`: the service and the byte buffers live in .bss,
    // not on the stack, and there is no allocator. The service starts as `new()`, which is all
    // zero bytes: initialised `with_identity` it would be copied from an image of its size in flash.
    static mut SERVICE: DeviceService = DeviceService::new();
    static mut INBOX: pump::Inbox = pump::Inbox::new();
    static mut OUTBOX: pump::Outbox = pump::Outbox::new();

    defmt::info!(
        "needle-firmware {} on {}",
        env!("CARGO_PKG_VERSION"),
        board::NAME
    );
    let (mut board, parts) = board::init();
    SERVICE.set_identity(IDENTITY);
    let mut axes = board::axes(SERVICE, parts);
    pump::run(&mut board, &mut axes, SERVICE, INBOX, OUTBOX)
}
