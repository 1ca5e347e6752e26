//! `hil-sim`: a simulated needle-planner device on a pseudo-terminal or a TCP port.
//!
//! Prints the device's address (the /dev/pts path, or the TCP address) as the first line on
//! stdout, then serves until killed.

use anyhow::{Context, Result};
use clap::Parser;
use hil_sim::serve::{serve, ServeConfig};
use hil_sim::{DeviceService, LineConfig, IDENTITY};
use std::io::Write;
use std::net::TcpListener;

#[derive(Parser)]
#[command(name = "hil-sim", version, about = "Simulated needle-planner device")]
struct Args {
    /// Serve on this TCP address (e.g. 127.0.0.1:7878; port 0 picks a free one) instead of a pty.
    #[arg(long)]
    tcp: Option<String>,
    /// Fraction of bytes corrupted on the line, in each direction.
    #[arg(long, default_value_t = 0.0)]
    flip_rate: f64,
    /// Fraction of bytes lost on the line, in each direction.
    #[arg(long, default_value_t = 0.0)]
    drop_rate: f64,
    /// Fraction of bytes that start a burst of corrupted bytes, in each direction.
    #[arg(long, default_value_t = 0.0)]
    burst_rate: f64,
    /// Bytes corrupted by one burst.
    #[arg(long, default_value_t = 20)]
    burst_len: u32,
    /// Seed of the fault pattern.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Pace bytes as a UART at this baud rate would (8N1); 0 for no pacing.
    #[arg(long, default_value_t = 0)]
    baud: u32,
}

fn main() -> Result<()> {
    let a = Args::parse();
    for (name, rate) in [
        ("--flip-rate", a.flip_rate),
        ("--drop-rate", a.drop_rate),
        ("--burst-rate", a.burst_rate),
    ] {
        anyhow::ensure!((0.0..=1.0).contains(&rate), "{name} must be within 0 and 1");
    }
    let line = |seed| LineConfig {
        flip_rate: a.flip_rate,
        drop_rate: a.drop_rate,
        burst_rate: a.burst_rate,
        burst_len: a.burst_len,
        seed,
    };
    let config = ServeConfig {
        to_device: line(a.seed),
        to_host: line(a.seed.wrapping_add(1)),
        baud: (a.baud > 0).then_some(a.baud),
    };
    let mut device = Box::new(DeviceService::with_identity(IDENTITY));
    let mut out = std::io::stdout();
    if let Some(addr) = &a.tcp {
        let listener =
            TcpListener::bind(addr).with_context(|| format!("cannot listen on {addr}"))?;
        writeln!(out, "{}", listener.local_addr()?)?;
        out.flush()?;
        for (k, conn) in (0u64..).zip(listener.incoming()) {
            let mut conn = conn?;
            conn.set_nodelay(true)?;
            // Each connection its own fault pattern (a pty's line goes on from client to
            // client): the same seeds every time would give every session the same faults.
            let config = ServeConfig {
                to_device: line(a.seed.wrapping_add(2 * k)),
                to_host: line(a.seed.wrapping_add(2 * k + 1)),
                ..config
            };
            if let Err(e) = serve(&mut conn, &mut device, &config) {
                eprintln!("hil-sim: connection ended: {e}");
            }
        }
        return Ok(());
    }
    let (mut master, slave) =
        serialport::TTYPort::pair().context("cannot open a pseudo-terminal")?;
    let path = serialport::SerialPort::name(&slave).context("the pseudo-terminal has no name")?;
    writeln!(out, "{path}")?;
    out.flush()?;
    // `slave` stays open for the life of the process: without an open slave, reads on the master
    // fail (EIO) between two clients.
    loop {
        if let Err(e) = serve(&mut master, &mut device, &config) {
            eprintln!("hil-sim: {e}");
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
}
