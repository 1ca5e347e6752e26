//! QEMU's MPS2 AN386: a Cortex-M4 with FPU, the link on CMSDK APB UART0 (QEMU's serial0).
//!
//! The UART is polled: QEMU holds incoming bytes until the guest has read the previous one, so
//! nothing is lost while a form is being planned. Logs go out through semihosting (defmt). The
//! board drives simulated axes (`mps2_an386_axes`).

use super::mps2_an386_axes::SimulatedAxes;
use crate::link::Link;
use core::ptr::{read_volatile, write_volatile};

/// Board name, as `cargo xtask device-bench` reports it.
pub const NAME: &str = "mps2-an386";

const UART0: usize = 0x4000_4000;
const DATA: usize = UART0;
const STATE: usize = UART0 + 0x4;
const CTRL: usize = UART0 + 0x8;
const BAUDDIV: usize = UART0 + 0x10;
const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_RX_ENABLE: u32 = 0b11;
/// 25 MHz / 115200 on the FPGA board; QEMU only needs it to be at least 16.
const BAUD_DIVISOR: u32 = 217;

/// CMSDK UART0.
pub struct Uart0 {
    _private: (),
}

fn reg_read(addr: usize) -> u32 {
    // SAFETY: `addr` is one of UART0's 32-bit registers (listed above), always mapped on this
    // board; a volatile read has no other effect than the device's own (popping RX data).
    unsafe { read_volatile(addr as *const u32) }
}

fn reg_write(addr: usize, value: u32) {
    // SAFETY: `addr` is one of UART0's 32-bit registers (listed above), always mapped on this
    // board; only this module writes them.
    unsafe { write_volatile(addr as *mut u32, value) }
}

/// What the axes take: the core peripherals (SysTick), if not already taken.
pub type AxesParts = Option<cortex_m::Peripherals>;

/// Enables UART0 for transmit and receive.
pub fn init() -> (Uart0, AxesParts) {
    reg_write(BAUDDIV, BAUD_DIVISOR);
    reg_write(CTRL, CTRL_TX_RX_ENABLE);
    (Uart0 { _private: () }, cortex_m::Peripherals::take())
}

/// The simulated axes, on SysTick's clock (`None` if the core peripherals were already taken
/// or the motion set-up was refused: motion requests are then answered `NoMotion`).
pub fn axes(
    service: &mut planner_core::device::DeviceService,
    parts: AxesParts,
) -> Option<SimulatedAxes> {
    SimulatedAxes::attach(service, parts?.SYST)
}

/// The UART for the panic handler's last words (the main loop is gone by then).
pub fn panic_link() -> Uart0 {
    Uart0 { _private: () }
}

impl Link for Uart0 {
    fn read(&mut self, buf: &mut [u8]) -> usize {
        let mut n = 0;
        while n < buf.len() && reg_read(STATE) & STATE_RX_FULL != 0 {
            buf[n] = reg_read(DATA) as u8;
            n += 1;
        }
        n
    }

    fn write_all(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while reg_read(STATE) & STATE_TX_FULL != 0 {}
            reg_write(DATA, u32::from(b));
        }
    }
}

/// Ends the QEMU run with a failure status.
pub fn fatal_stop() -> ! {
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    // Without a debugger host, semihosting exit returns: park here.
    loop {
        cortex_m::asm::wfi();
    }
}
