//! A progress line on stderr for work that runs longer than a second (covering a label map's
//! segments): shown only where a command turned it on, the command prints no JSON, and stderr
//! is a terminal; cleared when the work is done, so what stays on the terminal is the report.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

static ON: AtomicBool = AtomicBool::new(false);

/// Turns progress lines on for this process (a command that prints a table, not JSON).
pub fn enable() {
    ON.store(true, Ordering::Relaxed);
}

/// One piece of work's progress line.
pub struct Progress {
    what: String,
    start: Instant,
    after: Duration,
    on: bool,
    shown: bool,
}

/// How long work runs before its line shows: a second, or `NEEDLE_PROGRESS_AFTER_MS` (so a test
/// can see the line without depending on the machine's speed).
fn after() -> Duration {
    std::env::var("NEEDLE_PROGRESS_AFTER_MS")
        .ok()
        .and_then(|v| v.parse().ok())
        .map_or(Duration::from_secs(1), Duration::from_millis)
}

impl Progress {
    /// Progress of `what`, shown from a second on when enabled and stderr is a terminal.
    pub fn new(what: impl Into<String>) -> Progress {
        Progress {
            what: what.into(),
            start: Instant::now(),
            after: after(),
            on: ON.load(Ordering::Relaxed) && std::io::stderr().is_terminal(),
            shown: false,
        }
    }

    /// Says that step `done` of `total` (`note`) begins.
    pub fn step(&mut self, done: usize, total: usize, note: &str) {
        if !self.on || self.start.elapsed() < self.after {
            return;
        }
        let mut err = std::io::stderr().lock();
        let _ = write!(err, "\r\x1b[K{}: {done}/{total} {note}", self.what);
        let _ = err.flush();
        self.shown = true;
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if self.shown {
            let _ = write!(std::io::stderr().lock(), "\r\x1b[K");
        }
    }
}
