//! Long work shows its progress on stderr when stderr is a terminal and the command prints no
//! JSON, and clears it; with `--json`, or when stderr is not a terminal, it says nothing:
//! `needle cover`, the covering of a scenario's anatomy in `needle simulate`, and `needle
//! benchmark`'s scenarios. The cover's line shows after a second of work;
//! `NEEDLE_PROGRESS_AFTER_MS=0` shows it at once, so the test does not hang on the machine's
//! speed.

use needle_e2e::anatomy_family::anatomy_case;
use needle_e2e::label_files::{write_nrrd, NrrdStyle};
use needle_e2e::needle;
use serialport::SerialPort;
use std::io::Read;
use std::process::Stdio;

/// Runs `needle args` with stderr on a pty; what it wrote there.
fn stderr_on_a_terminal(args: &[&str]) -> String {
    let (mut master, slave) = serialport::TTYPort::pair().expect("a pty");
    let slave_path = slave.name().expect("the pty's name");
    let slave_file = std::fs::OpenOptions::new()
        .write(true)
        .open(&slave_path)
        .unwrap();
    let status = needle()
        .args(args)
        .env("NEEDLE_PROGRESS_AFTER_MS", "0")
        .stdout(Stdio::null())
        .stderr(Stdio::from(slave_file))
        .status()
        .unwrap();
    assert!(status.success());
    // The slave stays open while the master is read: on Linux, a master whose slaves are all
    // closed may fail its reads.
    master
        .set_timeout(std::time::Duration::from_millis(300))
        .unwrap();
    let mut out = Vec::new();
    let mut buf = [0u8; 4096];
    while let Ok(n) = master.read(&mut buf) {
        if n == 0 {
            break;
        }
        out.extend_from_slice(&buf[..n]);
    }
    drop(slave);
    String::from_utf8_lossy(&out).into_owned()
}

#[test]
fn cover_shows_progress_on_a_terminal_only() {
    let dir = std::env::temp_dir().join(format!("needle-progress-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let case = anatomy_case(2, 0.6);
    let path = dir.join("big.nrrd");
    let style = NrrdStyle {
        space: "right-anterior-superior",
        gzip: true,
        pairs: &[],
    };
    write_nrrd(&path, &case.labels, &style);
    let file = path.to_str().unwrap();
    let shown = stderr_on_a_terminal(&["cover", file]);
    assert!(
        shown.contains("covering ") && shown.contains("/5 segment"),
        "{shown:?}"
    );
    assert!(shown.ends_with("\r\x1b[K"), "not cleared: {shown:?}");
    let quiet = stderr_on_a_terminal(&["cover", file, "--json"]);
    assert!(!quiet.contains("covering "), "{quiet:?}");
    let piped = needle()
        .args(["cover", file])
        .env("NEEDLE_PROGRESS_AFTER_MS", "0")
        .output()
        .unwrap();
    assert!(!String::from_utf8_lossy(&piped.stderr).contains("covering "));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `needle simulate` on a scenario with anatomy: the covering's line, then the runs' bar, on a
/// terminal; nothing with `--json` or piped.
#[test]
fn simulate_shows_the_covering_and_the_runs_on_a_terminal_only() {
    let file = needle_e2e::example("anatomy");
    let args = ["simulate", file.to_str().unwrap(), "--runs", "4"];
    let shown = stderr_on_a_terminal(&args);
    assert!(shown.contains("covering "), "{shown:?}");
    assert!(shown.contains("simulate "), "the runs' bar: {shown:?}");
    let json: Vec<&str> = args.iter().copied().chain(["--json"]).collect();
    let quiet = stderr_on_a_terminal(&json);
    assert!(
        !quiet.contains("covering ") && !quiet.contains("simulate "),
        "{quiet:?}"
    );
    let piped = needle()
        .args(args)
        .env("NEEDLE_PROGRESS_AFTER_MS", "0")
        .output()
        .unwrap();
    assert!(piped.status.success());
    assert!(!String::from_utf8_lossy(&piped.stderr).contains("covering "));
}

/// `needle benchmark` says each scenario as it is done on a terminal; with `--json` or piped,
/// stderr stays empty.
#[test]
fn benchmark_shows_its_scenarios_on_a_terminal_only() {
    let args = [
        "benchmark",
        "--scenarios",
        "2",
        "--runs",
        "2",
        "--threads",
        "1",
    ];
    let shown = stderr_on_a_terminal(&args);
    assert!(
        shown.contains("scenario 1/2 (seed 101)") && shown.contains("scenario 2/2 (seed 102)"),
        "{shown:?}"
    );
    let json: Vec<&str> = args.iter().copied().chain(["--json"]).collect();
    assert_eq!(stderr_on_a_terminal(&json), "");
    let piped = needle().args(args).output().unwrap();
    assert!(piped.status.success());
    assert_eq!(String::from_utf8_lossy(&piped.stderr), "");
}
