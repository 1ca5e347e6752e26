//! What a firmware measurement or test needs: the thumbv7em target, QEMU, the firmware images and
//! the instruction-count plugin.
//! Missing tools are installed (rustup target, `apt-get install qemu-system-arm`) when possible.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The firmware's target triple.
pub const TARGET: &str = "thumbv7em-none-eabihf";

fn succeeds(cmd: &mut Command) -> bool {
    cmd.stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

fn run(cmd: &mut Command, what: &str) -> Result<()> {
    let status = cmd.status().with_context(|| format!("running {what}"))?;
    if !status.success() {
        bail!("{what} failed ({status})");
    }
    Ok(())
}

/// Adds the thumbv7em target through rustup if it is missing.
pub fn ensure_target() -> Result<()> {
    let installed = Command::new("rustup")
        .args(["target", "list", "--installed"])
        .output()
        .map(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .any(|l| l.trim() == TARGET)
        })
        .unwrap_or(false);
    if !installed {
        eprintln!("installing the {TARGET} target (rustup target add {TARGET})");
        run(
            Command::new("rustup").args(["target", "add", TARGET]),
            "rustup target add",
        )?;
    }
    Ok(())
}

/// Whether `qemu-system-arm` runs here.
pub fn qemu_available() -> bool {
    succeeds(Command::new("qemu-system-arm").arg("--version"))
}

/// Installs QEMU with apt-get if it is missing (as root on Debian/Ubuntu), else explains how.
pub fn ensure_qemu() -> Result<()> {
    if qemu_available() {
        return Ok(());
    }
    let root = Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false);
    if root && succeeds(Command::new("apt-get").arg("--version")) {
        eprintln!("installing QEMU (apt-get install -y qemu-system-arm)");
        run(
            Command::new("apt-get").args(["update", "-qq"]),
            "apt-get update",
        )?;
        run(
            Command::new("apt-get")
                .args(["install", "-y", "-qq", "qemu-system-arm"])
                .env("DEBIAN_FRONTEND", "noninteractive"),
            "apt-get install qemu-system-arm",
        )?;
    }
    if !qemu_available() {
        bail!("qemu-system-arm is missing: install it (Debian: apt-get install qemu-system-arm)");
    }
    Ok(())
}

/// A cargo command for a crate outside the host workspace: run from its directory (so its
/// `.cargo/config.toml` applies), with the caller's rustflags and target dir left out.
fn cargo_in(dir: &Path) -> Command {
    let mut cmd = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    cmd.current_dir(dir);
    for var in [
        "RUSTFLAGS",
        "CARGO_ENCODED_RUSTFLAGS",
        "CARGO_BUILD_RUSTFLAGS",
        "CARGO_TARGET_DIR",
        "CARGO_BUILD_TARGET",
    ] {
        cmd.env_remove(var);
    }
    cmd
}

/// The image of `board` built by [`build_firmware`].
pub fn firmware_image(root: &Path, board: &str) -> PathBuf {
    root.join("firmware/target")
        .join(board)
        .join(TARGET)
        .join("release/needle-firmware")
}

/// Builds the release firmware of `board` with `features`. Each board has its own target
/// directory, so builds of different boards (by tests running at once, say) never overwrite
/// each other's image.
///
/// The build is independent of where the checkout and the cargo home lie ([`path_remaps`]): the
/// panic locations the image carries would otherwise make its flash figure depend on them.
pub fn build_firmware(root: &Path, board: &str, features: &str) -> Result<PathBuf> {
    let dir = root.join("firmware");
    let mut cmd = cargo_in(&dir);
    cmd.args(["build", "--release", "--features", features, "--target-dir"])
        .arg(dir.join("target").join(board));
    for remap in path_remaps(root) {
        cmd.arg("--config").arg(remap);
    }
    run(&mut cmd, &format!("cargo build (firmware, {features})"))?;
    Ok(firmware_image(root, board))
}

/// Cargo `--config` values that add `--remap-path-prefix` flags (appended to the target's
/// rustflags of firmware/.cargo/config.toml) rewriting the checkout and the cargo home to
/// fixed names, so that the image does not change with the directory it was built in.
pub fn path_remaps(root: &Path) -> Vec<String> {
    let root = root.canonicalize().unwrap_or_else(|_| root.to_path_buf());
    let cargo_home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")));
    let mut prefixes = vec![(root, "")];
    if let Some(home) = cargo_home {
        prefixes.push((home.canonicalize().unwrap_or(home), ""));
    }
    prefixes
        .into_iter()
        .map(|(from, to)| {
            let flag = format!("--remap-path-prefix={}/={to}", from.display());
            format!("target.{TARGET}.rustflags=[{flag:?}]")
        })
        .collect()
}

/// Builds the instruction-count plugin and returns the shared library's path.
pub fn build_plugin(root: &Path) -> Result<PathBuf> {
    let dir = root.join("tools").join("insn-count");
    run(
        cargo_in(&dir).args(["build", "--release"]),
        "cargo build (insn-count plugin)",
    )?;
    Ok(dir.join("target").join("release").join("libinsn_count.so"))
}
