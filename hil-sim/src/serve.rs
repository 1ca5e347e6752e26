//! Serving the simulated device on a byte stream (a pty master or a TCP connection).

use crate::axes::SimulatedAxes;
use crate::line::{FaultyLine, LineConfig, Pacer};
use planner_core::device::DeviceService;
use std::io::{self, ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

/// A byte stream whose reads give up after a while.
pub trait Stream: Read + Write {
    /// How long a read waits for the first byte.
    fn set_wait(&mut self, wait: Duration) -> io::Result<()>;
    /// Reads what has arrived without waiting (`WouldBlock` or `TimedOut` if nothing has).
    fn read_now(&mut self, buf: &mut [u8]) -> io::Result<usize>;
}

impl Stream for TcpStream {
    fn set_wait(&mut self, wait: Duration) -> io::Result<()> {
        self.set_read_timeout(Some(wait))
    }

    // A socket's read timeout counts in scheduler ticks (4-10 ms), far longer than a form takes
    // to plan here: a non-blocking read keeps the simulated device as fast as the real one.
    fn read_now(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.set_nonblocking(true)?;
        let r = self.read(buf);
        self.set_nonblocking(false)?;
        r
    }
}

impl Stream for serialport::TTYPort {
    fn set_wait(&mut self, wait: Duration) -> io::Result<()> {
        serialport::SerialPort::set_timeout(self, wait).map_err(io::Error::from)
    }

    fn read_now(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.set_wait(Duration::ZERO)?;
        self.read(buf)
    }
}

/// The line between the stream and the device.
#[derive(Clone, Copy, Debug, Default)]
pub struct ServeConfig {
    /// Faults on bytes going to the device.
    pub to_device: LineConfig,
    /// Faults on bytes coming from the device.
    pub to_host: LineConfig,
    /// Baud rate to pace both directions at (none: as fast as the stream goes).
    pub baud: Option<u32>,
}

/// Runs `device` on `stream` until the stream ends (EOF) or fails.
///
/// One device poll per turn, so progress reports leave as each form finishes and requests that
/// arrive while planning are read between forms.
pub fn serve(
    stream: &mut dyn Stream,
    device: &mut DeviceService,
    config: &ServeConfig,
) -> io::Result<()> {
    serve_with_axes(stream, device, config, None)
}

/// [`serve`], with simulated axes behind the device's motion core (`hil-sim --axes`): they
/// move in real time, advanced by the time each turn took.
pub fn serve_with_axes(
    stream: &mut dyn Stream,
    device: &mut DeviceService,
    config: &ServeConfig,
    mut axes: Option<&mut SimulatedAxes>,
) -> io::Result<()> {
    let mut clock = Instant::now();
    let mut to_device = FaultyLine::new(config.to_device);
    let mut to_host = FaultyLine::new(config.to_host);
    let (mut rx_pace, mut tx_pace) = (Pacer::new(config.baud), Pacer::new(config.baud));
    let mut buf = [0u8; 512];
    let (mut carried, mut sent) = (Vec::new(), Vec::new());
    let mut busy = false;
    loop {
        let got = if busy {
            stream.read_now(&mut buf)
        } else {
            stream.set_wait(Duration::from_millis(20))?;
            stream.read(&mut buf)
        };
        match got {
            Ok(0) => return Ok(()),
            Ok(n) => {
                rx_pace.wait(n);
                carried.clear();
                to_device.carry(&buf[..n], &mut carried);
                let mut rest = &carried[..];
                while !rest.is_empty() {
                    let taken = device.receive_partial(rest);
                    rest = &rest[taken..];
                    if taken == 0 {
                        sent.clear();
                        device.poll(&mut |b: &[u8]| sent.extend_from_slice(b));
                        send_out(stream, &mut to_host, &mut tx_pace, &sent)?;
                    }
                }
            }
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) => {}
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        }
        sent.clear();
        busy = device.poll(&mut |b: &[u8]| sent.extend_from_slice(b));
        send_out(stream, &mut to_host, &mut tx_pace, &sent)?;
        if let Some(axes) = axes.as_deref_mut() {
            let ms = clock.elapsed().as_millis();
            if ms > 0 {
                clock += Duration::from_millis(ms as u64);
                axes.advance(device, u32::try_from(ms).unwrap_or(u32::MAX));
            }
        }
    }
}

fn send_out(
    stream: &mut dyn Stream,
    line: &mut FaultyLine,
    pace: &mut Pacer,
    sent: &[u8],
) -> io::Result<()> {
    if sent.is_empty() {
        return Ok(());
    }
    let mut carried = Vec::with_capacity(sent.len());
    line.carry(sent, &mut carried);
    pace.wait(sent.len());
    stream.write_all(&carried)?;
    stream.flush()
}
