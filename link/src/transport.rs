//! Byte transports to a device: a serial port or a TCP socket, both with read timeouts.

use anyhow::{Context, Result};
use std::io::{self, ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::Duration;

/// Moves bytes to and from a device.
pub trait Transport {
    /// Sends all of `bytes`.
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Reads what has arrived, waiting at most `timeout` for the first byte; `Ok(0)` on timeout
    /// (a transport that knows at once that nothing will come may return `Ok(0)` early).
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize>;
    /// The longest pause between two bytes of one frame: a frame still open after this long has
    /// lost its closing delimiter. Devices send each frame whole.
    fn frame_gap(&self) -> Duration {
        FRAME_GAP
    }
}

/// [`Transport::frame_gap`] of a link that carries a frame at once (TCP, in-process).
pub const FRAME_GAP: Duration = Duration::from_millis(5);

/// Where the device is.
#[derive(Clone, Debug)]
pub enum LinkTarget {
    /// A serial port (e.g. /dev/ttyACM0, a /dev/pts path from `hil-sim`) at a baud rate.
    Serial {
        /// Port path.
        path: String,
        /// Baud rate.
        baud: u32,
    },
    /// A TCP address (QEMU's `-serial tcp:...`, `hil-sim --tcp`).
    Tcp(String),
}

impl std::fmt::Display for LinkTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkTarget::Serial { path, baud } => write!(f, "{path} at {baud} baud"),
            LinkTarget::Tcp(addr) => write!(f, "tcp {addr}"),
        }
    }
}

impl<T: Transport + ?Sized> Transport for Box<T> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        (**self).send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        (**self).recv(buf, timeout)
    }
    fn frame_gap(&self) -> Duration {
        (**self).frame_gap()
    }
}

struct Serial(Box<dyn serialport::SerialPort>, u32);

impl Transport for Serial {
    /// Twenty byte times (8N1), at least [`FRAME_GAP`].
    fn frame_gap(&self) -> Duration {
        let byte = Duration::from_secs_f64(10.0 / f64::from(self.1.max(1)));
        (byte * 20).max(FRAME_GAP)
    }

    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.0.write_all(bytes)?;
        self.0.flush()
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.0.set_timeout(timeout).map_err(io::Error::from)?;
        match self.0.read(buf) {
            Err(e) if e.kind() == ErrorKind::TimedOut => Ok(0),
            other => other,
        }
    }
}

struct Tcp(TcpStream);

impl Transport for Tcp {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.0.write_all(bytes)
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.0
            .set_read_timeout(Some(timeout.max(Duration::from_millis(1))))?;
        match self.0.read(buf) {
            Ok(0) => Err(io::Error::new(
                ErrorKind::UnexpectedEof,
                "the device closed the connection",
            )),
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) => Ok(0),
            other => other,
        }
    }
}

/// A transport on a connected TCP stream (QEMU's UART once it accepted the connection, say).
pub fn tcp(stream: TcpStream) -> io::Result<Box<dyn Transport>> {
    // Frames are small and each waits for an answer: send them at once.
    stream.set_nodelay(true)?;
    Ok(Box::new(Tcp(stream)))
}

/// Opens the link.
pub fn open(target: &LinkTarget) -> Result<Box<dyn Transport>> {
    match target {
        LinkTarget::Serial { path, baud } => {
            let port = serialport::new(path, *baud)
                .timeout(Duration::from_millis(100))
                .open()
                .with_context(|| format!("cannot open serial port {path}"))?;
            // Bytes a previous session left in the buffers would only be skipped as garbage.
            let _ = port.clear(serialport::ClearBuffer::All);
            Ok(Box::new(Serial(port, *baud)))
        }
        LinkTarget::Tcp(addr) => {
            let s =
                TcpStream::connect(addr).with_context(|| format!("cannot connect to {addr}"))?;
            Ok(tcp(s)?)
        }
    }
}
