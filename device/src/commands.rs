//! The device commands of `needle`: how to reach the device, `ping`, `info`, `ports` (`send`
//! is in [`super::send`]); their flags are the `needle` binary's.

use anyhow::{bail, Context, Result};
use needle_link::{open, Client, ClientConfig, LinkTarget, Transport};
use planner_core::wire::DeviceInfo;
use std::io::Write;
use std::time::Duration;

/// The baud rate of a serial port when none is given.
pub const DEFAULT_BAUD: u32 = 115_200;

/// How to reach the device, shared by `send`, `ping`, `info` and `motion` (the `needle` binary
/// reads it from its flags, the Python package's `Device` from its arguments).
#[derive(Clone, Debug)]
pub struct LinkOptions {
    /// Serial port of the device (used when `tcp` is not given).
    pub port: Option<String>,
    /// Baud rate of the serial port.
    pub baud: u32,
    /// TCP address of the device instead of a serial port (QEMU, `hil-sim --tcp`).
    pub tcp: Option<String>,
    /// Seconds of silence allowed per exchange, and the longest silence while it plans.
    pub timeout: f64,
    /// Times one request is repeated before giving up.
    pub retries: u32,
    /// Seconds the whole command (greeting, upload, planning, fetch) may take.
    pub deadline: f64,
}

impl Default for LinkOptions {
    /// The client's defaults, for no device yet.
    fn default() -> Self {
        LinkOptions {
            port: None,
            baud: DEFAULT_BAUD,
            tcp: None,
            timeout: ClientConfig::DEFAULT.timeout.as_secs_f64(),
            retries: ClientConfig::DEFAULT.retries,
            deadline: ClientConfig::DEFAULT
                .deadline
                .map_or(120.0, |d| d.as_secs_f64()),
        }
    }
}

impl LinkOptions {
    /// The link of a command whose device is optional (`--tcp` or `--port`, else in-process):
    /// the client's default retries and a 120 s deadline.
    pub fn optional(
        port: &Option<String>,
        baud: u32,
        tcp: &Option<String>,
        timeout: f64,
    ) -> Option<LinkOptions> {
        (tcp.is_some() || port.is_some()).then(|| LinkOptions {
            port: port.clone(),
            baud,
            tcp: tcp.clone(),
            timeout,
            retries: ClientConfig::DEFAULT.retries,
            deadline: 120.0,
        })
    }

    /// Where the device is.
    pub fn target(&self) -> LinkTarget {
        match (&self.tcp, &self.port) {
            (Some(addr), _) => LinkTarget::Tcp(addr.clone()),
            (None, Some(path)) => LinkTarget::Serial {
                path: path.clone(),
                baud: self.baud,
            },
            // Neither: an empty address, which fails to open and says so (the `needle` binary
            // requires one of the two).
            (None, None) => LinkTarget::Tcp(String::new()),
        }
    }

    /// The retry policy's bounds, checked.
    pub fn config(&self) -> Result<ClientConfig> {
        for (name, v) in [("--timeout", self.timeout), ("--deadline", self.deadline)] {
            if !(v > 0.0 && v <= 1e6) {
                bail!("{name} must be a positive number of seconds (at most 1e6), not {v}");
            }
        }
        Ok(ClientConfig {
            timeout: Duration::from_secs_f64(self.timeout),
            retries: self.retries,
            deadline: Some(Duration::from_secs_f64(self.deadline)),
        })
    }

    /// Opens the link and greets the device (the protocol version is checked here); everything
    /// the client does from now on ends within `--deadline`.
    pub fn connect(&self) -> Result<(Client<Box<dyn Transport>>, DeviceInfo)> {
        let config = self.config()?;
        self.connect_within(config, config.deadline.unwrap_or(Duration::MAX))
    }

    /// Like `connect`, all within `limit`.
    pub fn connect_within(
        &self,
        config: ClientConfig,
        limit: Duration,
    ) -> Result<(Client<Box<dyn Transport>>, DeviceInfo)> {
        let target = self.target();
        let link = open(&target)?;
        let mut client = Client::new(link, config);
        client.set_deadline(limit);
        let info = client
            .hello()
            .with_context(|| format!("no planner device on {target}"))?;
        Ok((client, info))
    }
}

/// `needle ping`: round-trip times.
pub fn ping(link: &LinkOptions, count: u32) -> Result<()> {
    let (mut client, info) = link.connect()?;
    for i in 0..count.max(1) {
        let rtt = client.ping()?;
        writeln!(
            std::io::stdout(),
            "pong from {} ({}): seq={} time={:.3} ms",
            info.name,
            link.target(),
            i + 1,
            rtt.as_secs_f64() * 1e3
        )?;
    }
    let s = client.stats();
    if s.retried > 0 {
        writeln!(
            std::io::stdout(),
            "{} frames sent again, {} damaged frames detected",
            s.retried,
            s.detected
        )?;
    }
    Ok(())
}

/// The object `needle info --json` prints.
pub fn info_json(info: &DeviceInfo) -> serde_json::Value {
    serde_json::json!({
        "protocol": info.protocol,
        "name": info.name.as_str(),
        "firmware": info.firmware.as_str(),
        "build": info.build.as_str(),
        "max_obstacles": info.max_obstacles,
        "max_control_degree": info.max_control_degree,
        "form_count": info.form_count,
        "max_chunk": info.max_chunk,
        "upload_capacity": info.upload_capacity,
    })
}

/// `needle info`: who the device is and what it holds.
pub fn info(link: &LinkOptions, json: bool) -> Result<()> {
    let (_, info) = link.connect()?;
    if json {
        writeln!(std::io::stdout(), "{}", info_json(&info))?;
    } else {
        writeln!(std::io::stdout(), "device:             {}", info.name)?;
        writeln!(std::io::stdout(), "firmware:           {}", info.firmware)?;
        writeln!(std::io::stdout(), "build:              {}", info.build)?;
        writeln!(std::io::stdout(), "protocol:           {}", info.protocol)?;
        writeln!(
            std::io::stdout(),
            "max obstacles:      {}",
            info.max_obstacles
        )?;
        writeln!(
            std::io::stdout(),
            "max control degree: {}",
            info.max_control_degree
        )?;
        writeln!(std::io::stdout(), "path forms:         {}", info.form_count)?;
        writeln!(
            std::io::stdout(),
            "chunk size:         {} bytes",
            info.max_chunk
        )?;
        writeln!(
            std::io::stdout(),
            "upload capacity:    {} bytes",
            info.upload_capacity
        )?;
    }
    Ok(())
}

/// `needle ports`: serial ports with their USB ids.
pub fn ports() -> Result<()> {
    let ports = serialport::available_ports().context("cannot list serial ports")?;
    if ports.is_empty() {
        writeln!(std::io::stdout(), "no serial ports found")?;
    }
    for p in ports {
        match p.port_type {
            serialport::SerialPortType::UsbPort(u) => writeln!(
                std::io::stdout(),
                "{}  usb {:04x}:{:04x}  {}  {}{}",
                p.port_name,
                u.vid,
                u.pid,
                u.manufacturer.as_deref().unwrap_or("-"),
                u.product.as_deref().unwrap_or("-"),
                u.serial_number
                    .map(|s| format!("  serial {s}"))
                    .unwrap_or_default()
            )?,
            serialport::SerialPortType::PciPort => {
                writeln!(std::io::stdout(), "{}  pci", p.port_name)?
            }
            serialport::SerialPortType::BluetoothPort => {
                writeln!(std::io::stdout(), "{}  bluetooth", p.port_name)?
            }
            serialport::SerialPortType::Unknown => {
                writeln!(std::io::stdout(), "{}  unknown", p.port_name)?
            }
        }
    }
    Ok(())
}
