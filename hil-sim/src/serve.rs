//! Serving the simulated device on a byte stream (a pty master or a TCP connection).

use crate::line::{FaultyLine, LineConfig, Pacer};
use planner_core::device::DeviceService;
use std::io::{self, ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::Duration;

/// A byte stream whose reads give up after a while.
pub trait Stream: Read + Write {
    /// How long a read waits for the first byte.
    fn set_wait(&mut self, wait: Duration) -> io::Result<()>;
}

impl Stream for TcpStream {
    fn set_wait(&mut self, wait: Duration) -> io::Result<()> {
        self.set_read_timeout(Some(wait))
    }
}

impl Stream for serialport::TTYPort {
    fn set_wait(&mut self, wait: Duration) -> io::Result<()> {
        serialport::SerialPort::set_timeout(self, wait).map_err(io::Error::from)
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
    let mut to_device = FaultyLine::new(config.to_device);
    let mut to_host = FaultyLine::new(config.to_host);
    let (mut rx_pace, mut tx_pace) = (Pacer::new(config.baud), Pacer::new(config.baud));
    let mut buf = [0u8; 512];
    let (mut carried, mut sent) = (Vec::new(), Vec::new());
    let mut busy = false;
    loop {
        stream.set_wait(if busy {
            Duration::from_millis(1)
        } else {
            Duration::from_millis(20)
        })?;
        match stream.read(&mut buf) {
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
