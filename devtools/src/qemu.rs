//! One QEMU run of a firmware image: the UART on a local TCP port, the instruction-count plugin
//! loaded, and the monitor on a unix socket to read the painted stack back at the end.

use anyhow::{bail, Context, Result};
use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// One report of the plugin: `<sum> instructions in <regions> regions, largest <max>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Report {
    /// Instructions in all the regions since the last report.
    pub sum: u64,
    /// Regions since the last report.
    pub regions: u64,
    /// The largest single region.
    pub largest: u64,
}

impl Report {
    fn parse(line: &str) -> Option<Report> {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [sum, "instructions", "in", regions, "regions,", "largest", largest] => Some(Report {
                sum: sum.parse().ok()?,
                regions: regions.parse().ok()?,
                largest: largest.parse().ok()?,
            }),
            _ => None,
        }
    }
}

/// A running emulator.
pub struct Qemu {
    child: Child,
    /// The guest's UART.
    pub port: u16,
    monitor: PathBuf,
    counts: PathBuf,
    dir: PathBuf,
}

fn free_port() -> Result<u16> {
    // The port is free now; QEMU binds it a moment later (a small race, retried by the caller).
    Ok(TcpListener::bind("127.0.0.1:0")?.local_addr()?.port())
}

impl Qemu {
    /// Starts `machine` running `elf` with `plugin`; scratch files go to `dir`.
    /// With `profile`, the plugin also writes per-block counts to `dir/profile.txt` at exit.
    pub fn start(
        machine: &str,
        elf: &Path,
        plugin: &Path,
        dir: &Path,
        profile: bool,
    ) -> Result<Qemu> {
        std::fs::create_dir_all(dir)?;
        let port = free_port()?;
        let monitor = dir.join("monitor.sock");
        let counts = dir.join("insn-count.txt");
        let _ = std::fs::remove_file(&monitor);
        let _ = std::fs::remove_file(&counts);
        let mut plugin_arg = format!("{},out={}", plugin.display(), counts.display());
        if profile {
            plugin_arg.push_str(&format!(",profile={}", dir.join("profile.txt").display()));
        }
        let stdout = std::fs::File::create(dir.join("qemu-stdout.defmt"))?;
        let stderr = std::fs::File::create(dir.join("qemu-stderr.txt"))?;
        let child = Command::new("qemu-system-arm")
            .args(["-M", machine, "-display", "none", "-kernel"])
            .arg(elf)
            .args(["-semihosting-config", "enable=on,target=native"])
            .arg("-serial")
            .arg(format!("tcp:127.0.0.1:{port},server=on,wait=on"))
            .arg("-monitor")
            .arg(format!("unix:{},server=on,wait=off", monitor.display()))
            .arg("-plugin")
            .arg(plugin_arg)
            .args(["-d", "plugin", "-D"])
            .arg(dir.join("qemu-log.txt"))
            .stdin(Stdio::null())
            .stdout(stdout)
            .stderr(stderr)
            .spawn()
            .context("starting qemu-system-arm")?;
        Ok(Qemu {
            child,
            port,
            monitor,
            counts,
            dir: dir.to_path_buf(),
        })
    }

    /// Connects to the guest's UART (QEMU starts the guest once this connection is made).
    pub fn connect(&mut self) -> Result<TcpStream> {
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            if let Some(status) = self.child.try_wait()? {
                let log =
                    std::fs::read_to_string(self.dir.join("qemu-stderr.txt")).unwrap_or_default();
                bail!(
                    "QEMU exited ({status}) before the UART connected: {}",
                    log.trim()
                );
            }
            match TcpStream::connect(("127.0.0.1", self.port)) {
                Ok(s) => return Ok(s),
                Err(_) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(50))
                }
                Err(e) => return Err(e).context("connecting to QEMU's UART"),
            }
        }
    }

    /// The plugin's reports so far: instructions per plan, in order.
    pub fn counts(&self) -> Result<Vec<u64>> {
        Ok(self.reports()?.iter().map(|r| r.sum).collect())
    }

    /// The plugin's reports so far, whole, in order.
    pub fn reports(&self) -> Result<Vec<Report>> {
        let text = std::fs::read_to_string(&self.counts).unwrap_or_default();
        text.lines()
            .filter_map(|l| l.strip_prefix("insn-count: "))
            .filter(|l| l.contains(" in "))
            .map(|l| Report::parse(l).with_context(|| format!("bad plugin line {l:?}")))
            .collect()
    }

    /// Reads `len` bytes of guest memory at `addr` (through the monitor's `pmemsave`), then stops
    /// QEMU.
    pub fn read_memory_and_quit(mut self, addr: u32, len: u32) -> Result<Vec<u8>> {
        let dump = self.dir.join("memory.bin");
        let _ = std::fs::remove_file(&dump);
        let stream = UnixStream::connect(&self.monitor).context("connecting to QEMU's monitor")?;
        stream.set_read_timeout(Some(Duration::from_secs(30)))?;
        let mut writer = stream.try_clone()?;
        let mut reader = BufReader::new(stream);
        wait_prompt(&mut reader)?;
        writeln!(writer, "pmemsave {addr:#x} {len:#x} \"{}\"", dump.display())?;
        wait_prompt(&mut reader)?;
        writeln!(writer, "quit")?;
        // QEMU writes the plugin's exit report (and profile) as it quits.
        let _ = self.child.wait();
        let memory = std::fs::read(&dump).context("QEMU wrote no memory dump")?;
        if memory.len() != len as usize {
            bail!("memory dump holds {} bytes, not {len}", memory.len());
        }
        Ok(memory)
    }
}

/// Reads monitor output up to its next `(qemu) ` prompt.
fn wait_prompt(reader: &mut impl BufRead) -> Result<()> {
    let mut seen = Vec::new();
    let mut byte = [0u8; 1];
    while !seen.ends_with(b"(qemu) ") {
        if reader.read(&mut byte).context("reading QEMU's monitor")? == 0 {
            bail!("QEMU's monitor closed");
        }
        seen.push(byte[0]);
    }
    Ok(())
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
