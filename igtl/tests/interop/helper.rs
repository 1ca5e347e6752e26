//! The Python helpers of `tests/python/`, run by the venv `scripts/python-env` makes: every wait
//! has a deadline, and a helper is killed when its guard drops, so a failed assertion leaves no
//! process behind.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

/// The interpreter with pyigtl: `$NEEDLE_PYTHON`, else `target/python-env/bin/python` at the
/// repository's root. Missing, the tests fail: skipping would pass without checking anything.
pub fn python() -> PathBuf {
    let path = std::env::var_os("NEEDLE_PYTHON").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/python-env/bin/python"),
        PathBuf::from,
    );
    assert!(
        path.exists(),
        "no Python with pyigtl at {}: run scripts/python-env (scripts/test-all does)",
        path.display()
    );
    path
}

/// A running helper script: its stdout as it comes, its stderr for failure messages.
pub struct Helper {
    name: String,
    child: Child,
    stdout: Receiver<Vec<u8>>,
    pending: Vec<u8>,
    stderr: Option<JoinHandle<String>>,
}

impl Helper {
    /// Starts `tests/python/<script>` with `args`.
    pub fn start(script: &str, args: &[&str]) -> Helper {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/python")
            .join(script);
        let mut child = Command::new(python())
            .arg(&path)
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", path.display()));
        // Reader threads: a pipe read has no timeout, a channel receive does.
        let mut out = child.stdout.take().expect("piped stdout");
        let (tx, stdout) = mpsc::channel();
        thread::spawn(move || {
            let mut buf = [0u8; 8192];
            while let Ok(n @ 1..) = out.read(&mut buf) {
                if tx.send(buf[..n].to_vec()).is_err() {
                    break;
                }
            }
        });
        let mut err = child.stderr.take().expect("piped stderr");
        let stderr = thread::spawn(move || {
            let mut text = String::new();
            let _ = err.read_to_string(&mut text);
            text
        });
        Helper {
            name: script.to_string(),
            child,
            stdout,
            pending: Vec::new(),
            stderr: Some(stderr),
        }
    }

    /// The next line of stdout (without its newline), by `deadline`.
    pub fn line(&mut self, deadline: Instant) -> String {
        loop {
            if let Some(i) = self.pending.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.pending.drain(..=i).collect();
                return String::from_utf8_lossy(&line[..i]).into_owned();
            }
            if !self.read_more(deadline) {
                self.fail("closed stdout before a whole line");
            }
        }
    }

    /// Fails the test with the helper's stderr if it has exited.
    pub fn check_running(&mut self) {
        if let Ok(Some(status)) = self.child.try_wait() {
            self.fail(&format!("exited early ({status})"));
        }
    }

    /// Waits by `deadline` for the helper to close stdout and exit 0; returns the stdout not yet
    /// taken as lines.
    pub fn finish(mut self, deadline: Instant) -> Vec<u8> {
        while self.read_more(deadline) {}
        let status = self.wait(deadline);
        if !status.success() {
            self.fail(&format!("exited with {status}"));
        }
        std::mem::take(&mut self.pending)
    }

    /// Appends what stdout has next; false once it is closed.
    fn read_more(&mut self, deadline: Instant) -> bool {
        let left = deadline.saturating_duration_since(Instant::now());
        match self.stdout.recv_timeout(left) {
            Ok(bytes) => {
                self.pending.extend_from_slice(&bytes);
                true
            }
            Err(RecvTimeoutError::Disconnected) => false,
            Err(RecvTimeoutError::Timeout) => self.fail("timed out"),
        }
    }

    fn wait(&mut self, deadline: Instant) -> ExitStatus {
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return status,
                Ok(None) if Instant::now() < deadline => thread::sleep(Duration::from_millis(10)),
                Ok(None) => self.fail("did not exit in time"),
                Err(e) => self.fail(&format!("cannot wait for it: {e}")),
            }
        }
    }

    /// Kills the helper and fails the test with its stderr.
    fn fail(&mut self, why: &str) -> ! {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let stderr = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        panic!("{}: {why}\n--- its stderr ---\n{stderr}", self.name)
    }
}

impl Drop for Helper {
    fn drop(&mut self) {
        // Harmless when it has exited already.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
