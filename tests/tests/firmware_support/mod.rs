//! Shared helpers of the `firmware_*` tests: toolchain and QEMU checks, firmware builds, and a
//! QEMU process with the guest's UART on a local TCP port.
#![allow(dead_code)]

use needle_devtools::firmware_artifacts as artifacts;
use needle_e2e::workspace;
use std::net::{TcpListener, TcpStream};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// Whether the firmware can be built and emulated here. Adds the rustup target if missing.
/// Without QEMU: under CI (`CI=true`) it is installed (`scripts/install-emulator`) and a failure
/// to do so fails the test; elsewhere the test is skipped with a note.
pub fn emulator_ready(test: &str) -> bool {
    if let Err(e) = artifacts::ensure_target() {
        panic!("{e:#}");
    }
    if artifacts::qemu_available() {
        return true;
    }
    if in_ci() {
        let script = workspace().join("scripts/install-emulator");
        let _ = Command::new("bash").arg(script).status();
        assert!(
            artifacts::qemu_available(),
            "CI=true and qemu-system-arm is missing and could not be installed"
        );
        return true;
    }
    eprintln!(
        "{test}: SKIPPED, qemu-system-arm is not installed (apt-get install qemu-system-arm)"
    );
    false
}

/// Builds the release firmware for `board` (its own target dir, as `cargo xtask device-bench` does)
/// and returns the image.
pub fn build_firmware(board: &str, features: &str) -> PathBuf {
    match artifacts::build_firmware(&workspace(), board, features) {
        Ok(image) => image,
        Err(e) => panic!("building the {board} firmware: {e:#}"),
    }
}

/// QEMU running a firmware image, its UART on `addr`; killed (by its own handle) when dropped.
pub struct Qemu {
    child: Child,
    /// `127.0.0.1:PORT` of the guest's UART.
    pub addr: String,
    /// `127.0.0.1:PORT` of QEMU's debugger stub (`needle_devtools::gdb_remote` writes through it).
    pub debugger: String,
}

/// Two distinct free local ports (both held until both are known).
fn free_ports() -> (u16, u16) {
    let bind = || TcpListener::bind("127.0.0.1:0").expect("a free local port");
    let (a, b) = (bind(), bind());
    let port = |l: &TcpListener| l.local_addr().expect("a bound port").port();
    (port(&a), port(&b))
}

impl Qemu {
    /// Boots `image` on `machine` and waits until the UART's TCP server listens.
    pub fn start(machine: &str, image: &PathBuf) -> Qemu {
        let (port, gdb) = free_ports();
        let debugger = format!("127.0.0.1:{gdb}");
        let child = Command::new("qemu-system-arm")
            .args(["-M", machine, "-display", "none", "-monitor", "none"])
            .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
            .arg(image)
            .arg("-serial")
            .arg(format!("tcp:127.0.0.1:{port},server=on,wait=on"))
            .args(["-gdb", &format!("tcp:{debugger}")])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start qemu-system-arm");
        let mut qemu = Qemu {
            child,
            addr: format!("127.0.0.1:{port}"),
            debugger,
        };
        // A first connection starts the guest; closing it leaves QEMU listening for the next.
        let deadline = Instant::now() + Duration::from_secs(20);
        while TcpStream::connect(&qemu.addr).is_err() {
            assert!(qemu.running(), "QEMU exited at start");
            assert!(Instant::now() < deadline, "QEMU's UART never listened");
            std::thread::sleep(Duration::from_millis(50));
        }
        qemu
    }

    /// Whether the emulator is still running (the firmware stops it only after a fault).
    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
