//! USART1 on PA9 (TX) / PA10 (RX), AF7, 115200 8N1.
//!
//! Reception is interrupt-driven into a ring buffer: a form can take a noticeable fraction of a
//! second to plan, and the USART holds one byte, so polling would lose a cancel request sent
//! meanwhile. Transmission is polled (the service produces bytes between planning steps).

use super::clocks::Clocks;
use super::pac::{self, interrupt};
use super::watchdog::Watchdog;
use crate::link::Link;
use core::cell::RefCell;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::interrupt::Mutex;
use heapless::Deque;

const BAUD: u32 = 115_200;
/// Received bytes not yet handed to the service: about 90 ms of line time at 115200 baud.
const RX_BUFFER_BYTES: usize = 1024;
/// GPIO alternate function of USART1 on PA9/PA10.
const AF_USART1: u8 = 7;

static RX: Mutex<RefCell<Deque<u8, RX_BUFFER_BYTES>>> = Mutex::new(RefCell::new(Deque::new()));
static RX_DROPPED: AtomicU32 = AtomicU32::new(0);

/// USART1 with its receive interrupt running.
pub struct Usart1 {
    usart: pac::USART1,
    watchdog: Watchdog,
    dropped_reported: u32,
}

impl Usart1 {
    /// Routes PA9/PA10 to USART1, sets 115200 8N1 and enables the receive interrupt.
    pub fn init(
        usart: pac::USART1,
        rcc: &pac::RCC,
        gpioa: &pac::GPIOA,
        clocks: Clocks,
        watchdog: Watchdog,
    ) -> Self {
        rcc.ahb1enr().modify(|_, w| w.gpioaen().set_bit());
        rcc.apb2enr().modify(|_, w| w.usart1en().set_bit());
        gpioa.afrh().modify(|_, w| {
            w.afrh9().set(AF_USART1);
            w.afrh10().set(AF_USART1)
        });
        gpioa.pupdr().modify(|_, w| w.pupdr10().pull_up());
        gpioa.moder().modify(|_, w| {
            w.moder9().alternate();
            w.moder10().alternate()
        });
        let divisor = (clocks.pclk2_hz + BAUD / 2) / BAUD;
        // BRR holds the divisor as mantissa:fraction (4 bits) with 16x oversampling, which is
        // the plain divisor read as one 16-bit number.
        usart.brr().write(|w| {
            w.div_mantissa().set((divisor >> 4) as u16);
            w.div_fraction().set((divisor & 0xF) as u8)
        });
        usart.cr1().write(|w| {
            w.ue().set_bit();
            w.te().set_bit();
            w.re().set_bit();
            w.rxneie().set_bit()
        });
        // SAFETY: NVIC register write. Unmasking is sound: the handler only touches `RX` (behind
        // a critical-section mutex), `RX_DROPPED` (atomic) and USART1's SR/DR.
        unsafe { cortex_m::peripheral::NVIC::unmask(pac::Interrupt::USART1) };
        Usart1 {
            usart,
            watchdog,
            dropped_reported: 0,
        }
    }
}

#[interrupt]
fn USART1() {
    // SAFETY: register access only: SR is read, then DR, which is the documented sequence that
    // clears RXNE and an overrun; the main loop touches only TXE (SR) and DR writes, which this
    // read does not disturb.
    let usart = unsafe { &*pac::USART1::ptr() };
    let sr = usart.sr().read();
    if sr.rxne().bit_is_set() || sr.ore().bit_is_set() {
        let byte = usart.dr().read().dr().bits() as u8;
        let overrun = sr.ore().bit_is_set();
        cortex_m::interrupt::free(|cs| {
            if RX.borrow(cs).borrow_mut().push_back(byte).is_err() || overrun {
                RX_DROPPED.fetch_add(1, Ordering::Relaxed);
            }
        });
    }
}

impl Link for Usart1 {
    fn read(&mut self, buf: &mut [u8]) -> usize {
        cortex_m::interrupt::free(|cs| {
            let mut rx = RX.borrow(cs).borrow_mut();
            let mut n = 0;
            while n < buf.len() {
                let Some(b) = rx.pop_front() else { break };
                buf[n] = b;
                n += 1;
            }
            n
        })
    }

    fn write_all(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while self.usart.sr().read().txe().bit_is_clear() {}
            self.usart.dr().write(|w| w.dr().set(u16::from(b)));
        }
    }

    fn service(&mut self) {
        self.watchdog.feed();
        let dropped = RX_DROPPED.load(Ordering::Relaxed);
        if dropped != self.dropped_reported {
            // The service sees the gap as a bad frame (CRC) and answers with an error reply.
            defmt::warn!("{=u32} received bytes lost in total", dropped);
            self.dropped_reported = dropped;
        }
    }
}

/// USART1 taken over by the panic handler.
pub struct PanicUsart {
    usart: &'static pac::usart1::RegisterBlock,
}

impl PanicUsart {
    /// Takes USART1 whatever state the main loop left it in.
    pub fn steal() -> Self {
        // SAFETY: register access from the panic handler, with interrupts disabled and the main
        // loop never returning: nothing else uses USART1 any more.
        let usart = unsafe { &*pac::USART1::ptr() };
        PanicUsart { usart }
    }
}

impl Link for PanicUsart {
    fn read(&mut self, _buf: &mut [u8]) -> usize {
        0
    }

    fn write_all(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while self.usart.sr().read().txe().bit_is_clear() {}
            self.usart.dr().write(|w| w.dr().set(u16::from(b)));
        }
    }
}
