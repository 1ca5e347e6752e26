//! The link as a USB CDC-ACM virtual serial port on the OTG_FS peripheral (PA11 D-, PA12 D+),
//! so the host sees `/dev/ttyACM0` (Linux) or a COM port and `needle send --port` works as over
//! a UART.
//!
//! The bus is polled from the service loop; between two polls the peripheral NAKs the host, which
//! retries, so one form's planning time only delays the link. USB needs the crystal (48 MHz from
//! the PLL within 0.25 %).
//!
//! The VID:PID is pid.codes' test pair (1209:0001): a product needs its own.

use super::clocks::Clocks;
use super::pac;
use super::watchdog::Watchdog;
use crate::link::Link;
use synopsys_usb_otg::{UsbBus, UsbPeripheral};
use usb_device::bus::UsbBusAllocator;
use usb_device::device::{
    StringDescriptors, UsbDevice, UsbDeviceBuilder, UsbDeviceState, UsbVidPid,
};
use usbd_serial::{SerialPort, USB_CLASS_CDC};

/// GPIO alternate function of OTG_FS on PA11/PA12.
const AF_OTG_FS: u8 = 10;
/// Bus polls to wait for the host to take reply bytes before dropping them.
const WRITE_PATIENCE: u32 = 200_000;

/// The OTG_FS peripheral for the bus driver. It is built only from the PAC handles of OTG_FS's
/// three register blocks, which `init` consumes, so nothing else can reach those registers.
pub struct OtgFs {
    hclk_hz: u32,
}

// SAFETY: the constants describe the STM32F405/407 OTG_FS block (RM0090 section 34: registers at
// 0x5000_0000, 1.25 KiB of FIFO RAM, 4 bidirectional endpoints), and `OtgFs` exists only once,
// made from the consumed PAC handles, so the bus driver is the only user of those registers.
unsafe impl UsbPeripheral for OtgFs {
    const REGISTERS: *const () = pac::OTG_FS_GLOBAL::PTR as *const ();
    const HIGH_SPEED: bool = false;
    const FIFO_DEPTH_WORDS: usize = 320;
    const ENDPOINT_COUNT: usize = 4;

    fn enable() {
        cortex_m::interrupt::free(|_| {
            // SAFETY: register access to RCC's AHB2 enable and reset registers, inside a
            // critical section so the read-modify-writes cannot interleave with other RCC users
            // (there are none after `init`).
            let rcc = unsafe { &*pac::RCC::ptr() };
            rcc.ahb2enr().modify(|_, w| w.otgfsen().set_bit());
            rcc.ahb2rstr().modify(|_, w| w.otgfsrst().set_bit());
            rcc.ahb2rstr().modify(|_, w| w.otgfsrst().clear_bit());
        });
    }

    fn ahb_frequency_hz(&self) -> u32 {
        self.hclk_hz
    }
}

type Bus = UsbBus<OtgFs>;

/// The USB device with its one CDC-ACM function.
pub struct UsbSerial {
    device: UsbDevice<'static, Bus>,
    serial: SerialPort<'static, Bus>,
    watchdog: Watchdog,
}

impl UsbSerial {
    /// Routes PA11/PA12 to OTG_FS and brings up the device (it enumerates from the service loop).
    pub fn init(
        global: pac::OTG_FS_GLOBAL,
        device: pac::OTG_FS_DEVICE,
        pwrclk: pac::OTG_FS_PWRCLK,
        rcc: &pac::RCC,
        gpioa: &pac::GPIOA,
        clocks: Clocks,
        watchdog: Watchdog,
    ) -> Self {
        if !clocks.hse {
            defmt::warn!("USB without the crystal: enumeration may fail");
        }
        rcc.ahb1enr().modify(|_, w| w.gpioaen().set_bit());
        gpioa.afrh().modify(|_, w| {
            w.afrh11().set(AF_OTG_FS);
            w.afrh12().set(AF_OTG_FS)
        });
        gpioa.ospeedr().modify(|_, w| {
            w.ospeedr11().very_high_speed();
            w.ospeedr12().very_high_speed()
        });
        gpioa.moder().modify(|_, w| {
            w.moder11().alternate();
            w.moder12().alternate()
        });
        let _consumed = (global, device, pwrclk);
        let otg = OtgFs {
            hclk_hz: clocks.sysclk_hz,
        };
        let ep_memory: &'static mut [u32; 320] = match cortex_m::singleton!(: [u32; 320] = [0; 320])
        {
            Some(m) => m,
            None => super::fatal_stop(),
        };
        let bus: &'static UsbBusAllocator<Bus> = match cortex_m::singleton!(: UsbBusAllocator<Bus> = UsbBus::new(otg, ep_memory))
        {
            Some(b) => b,
            None => super::fatal_stop(),
        };
        let serial = SerialPort::new(bus);
        let strings = StringDescriptors::default()
            .manufacturer("needle-planner")
            .product("needle planner")
            .serial_number(env!("CARGO_PKG_VERSION"));
        let device = match UsbDeviceBuilder::new(bus, UsbVidPid(0x1209, 0x0001))
            .strings(&[strings])
            .and_then(|b| b.max_packet_size_0(64))
        {
            Ok(builder) => builder.device_class(USB_CLASS_CDC).build(),
            Err(_) => super::fatal_stop(),
        };
        UsbSerial {
            device,
            serial,
            watchdog,
        }
    }

    fn poll_bus(&mut self) {
        self.device.poll(&mut [&mut self.serial]);
    }
}

impl Link for UsbSerial {
    fn read(&mut self, buf: &mut [u8]) -> usize {
        self.poll_bus();
        self.serial.read(buf).unwrap_or(0)
    }

    fn write_all(&mut self, mut bytes: &[u8]) {
        let mut patience = WRITE_PATIENCE;
        while !bytes.is_empty() {
            // Nobody has the port open (DTR low) or the host stopped reading: drop the reply
            // rather than wedge; the host's timeout and retry take over.
            if self.device.state() != UsbDeviceState::Configured
                || !self.serial.dtr()
                || patience == 0
            {
                defmt::warn!("dropped {=usize} reply bytes: no host reading", bytes.len());
                return;
            }
            self.poll_bus();
            match self.serial.write(bytes) {
                Ok(n) => bytes = &bytes[n..],
                Err(_) => patience -= 1,
            }
            self.watchdog.feed();
        }
    }

    fn service(&mut self) {
        self.watchdog.feed();
        self.poll_bus();
    }
}

/// No link for the panic handler: the USB stack needs the main loop.
pub struct NoLink;

impl Link for NoLink {
    fn read(&mut self, _buf: &mut [u8]) -> usize {
        0
    }

    fn write_all(&mut self, _bytes: &[u8]) {}
}
