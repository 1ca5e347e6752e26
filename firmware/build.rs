//! Puts the selected board's `memory.x` where cortex-m-rt's `link.x` finds it.

use std::{env, fs, path::PathBuf};

fn main() {
    // Target and profile for the protocol's hello (a commit id would go stale: this script only
    // reruns when the board layout changes).
    let target = env::var("TARGET").unwrap_or_default();
    let profile = env::var("PROFILE").unwrap_or_default();
    println!("cargo:rustc-env=NEEDLE_FIRMWARE_BUILD={target} {profile}");

    let boards = [
        ("CARGO_FEATURE_MPS2_AN386", "mps2-an386"),
        ("CARGO_FEATURE_STM32F4", "stm32f4"),
    ];
    let selected: Vec<&str> = boards
        .iter()
        .filter(|(var, _)| env::var_os(var).is_some())
        .map(|(_, name)| *name)
        .collect();
    // With no or two boards, main.rs stops the build with a clear message; link nothing here.
    let [board] = selected.as_slice() else { return };
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let layout = format!("boards/{board}/memory.x");
    fs::copy(&layout, out.join("memory.x")).expect("board memory.x exists");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={layout}");
    println!("cargo:rerun-if-changed=build.rs");
}
