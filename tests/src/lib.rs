//! Helpers for the end-to-end tests in `tests/`: finding (and if needed building) the `needle`
//! binary of the same build profile, and the paths of the example scenarios. Also the
//! independent reference planner that the optimality tests compare `planner-core` against.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

pub mod anatomy_family;
pub mod doc_figures;
pub mod label_files;
pub mod module_graph;
pub mod readme;
pub mod reference;
pub mod sampling;
pub mod soundness;

/// The workspace root.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits in the workspace")
        .to_path_buf()
}

/// The flags of the campaign's "clinical x2, lab-told" world (scripts/clinical-campaign.py):
/// `--world clinical` with every spread and effect doubled (`needle_sim::TWICE_CLINICAL_KEYS`,
/// `TWICE_CLINICAL_FAULT_KEYS`), the steering told `target_speed_walk = 0.02`.
pub fn twice_clinical_flags() -> Vec<String> {
    let mut flags: Vec<String> = ["--world", "clinical", "--steer", "target_speed_walk=0.02"]
        .map(String::from)
        .to_vec();
    for kv in needle_sim::TWICE_CLINICAL_KEYS {
        flags.extend(["--perturb".into(), kv.to_string()]);
    }
    for kv in needle_sim::TWICE_CLINICAL_FAULT_KEYS {
        flags.extend(["--fault".into(), kv.to_string()]);
    }
    flags
}

/// The interpreter of the venv `scripts/python-env` makes (pyigtl, nibabel, pynrrd):
/// `$NEEDLE_PYTHON`, else `target/python-env/bin/python`. Missing, the calling test fails:
/// skipping would pass without checking anything.
pub fn venv_python() -> PathBuf {
    let path = std::env::var_os("NEEDLE_PYTHON").map_or_else(
        || workspace().join("target/python-env/bin/python"),
        PathBuf::from,
    );
    assert!(
        path.exists(),
        "no Python of scripts/python-env at {}: run scripts/python-env",
        path.display()
    );
    path
}

/// Runs `tests/python/SCRIPT` with `args` in the venv of [`venv_python`]; its stdout. A script
/// that fails fails the calling test with its stderr.
pub fn venv_script<S: AsRef<std::ffi::OsStr>>(script: &str, args: &[S]) -> Vec<u8> {
    let run = Command::new(venv_python())
        .arg(workspace().join("tests/python").join(script))
        .args(args)
        .output()
        .expect("the venv's Python runs");
    assert!(
        run.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    run.stdout
}

/// An example scenario file by name (`paper`, `space`).
pub fn example(name: &str) -> PathBuf {
    workspace().join("examples").join(format!("{name}.toml"))
}

/// Path of the `needle` binary built with the profile running these tests; built on first use.
pub fn needle_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| built("needle-cli", "needle"))
}

/// Path of the `xtask` binary (`cargo xtask`'s tasks) built with the profile running these
/// tests; built on first use.
pub fn xtask_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| built("xtask", "xtask"))
}

/// Builds `bin` of the workspace's `package` with the profile running these tests (no package
/// of the workspace depends on a binary's package, so it is built here) and returns its path.
fn built(package: &str, bin: &str) -> PathBuf {
    // Test executables live in target/<profile-dir>/deps/.
    let exe = std::env::current_exe().expect("test executable path");
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps layout")
        .to_path_buf();
    let profile = match profile_dir.file_name().and_then(|n| n.to_str()) {
        Some("debug") => "dev".to_string(),
        Some(other) => other.to_string(),
        None => "dev".to_string(),
    };
    let status = Command::new(env!("CARGO"))
        .args(["build", "--quiet", "-p", package, "--bin", bin, "--profile"])
        .arg(&profile)
        .current_dir(workspace())
        .status()
        .expect("run cargo build");
    assert!(status.success(), "building {bin} failed");
    profile_dir.join(format!("{bin}{}", std::env::consts::EXE_SUFFIX))
}

/// A `cargo xtask` task ready for arguments (`xtask_bin`), run from the workspace root.
pub fn xtask() -> Command {
    let mut c = Command::new(xtask_bin());
    c.current_dir(workspace());
    c
}

/// A `needle` command ready for arguments, run from the workspace root.
pub fn needle() -> Command {
    let mut c = Command::new(needle_bin());
    c.current_dir(workspace());
    c
}

/// The keys of a JSON object, sorted (a JSON contract's test compares them).
pub fn json_keys(v: &serde_json::Value) -> Vec<String> {
    let mut k: Vec<String> = v
        .as_object()
        .map(|o| o.keys().cloned().collect())
        .unwrap_or_default();
    k.sort();
    k
}

/// Runs `needle` with `args`, asserts that it succeeds and returns what it printed, byte for
/// byte (compare these for bit-for-bit equality: parsing JSON may round a float's last bit).
pub fn needle_stdout(args: &[&str]) -> Vec<u8> {
    let out = needle().args(args).output().expect("run needle");
    assert!(
        out.status.success(),
        "needle {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// Runs `needle` with `args` (which ask for JSON), asserts that it succeeds and returns what it
/// printed.
pub fn needle_json(args: &[&str]) -> serde_json::Value {
    serde_json::from_slice(&needle_stdout(args)).expect("needle prints JSON")
}

/// The paper's scenario as an encoded plan request carrying `n` obstacles (any count the wire
/// carries, also over the planner's capacity), in the layout of `planner_core::wire::PlanRequest`.
pub fn request_with_obstacles(n: usize) -> Vec<u8> {
    use planner_core::model::scenario::Obstacle;
    let base = planner_core::wire::PlanRequest::new(&planner_core::Scenario::paper());
    let obstacles: Vec<Obstacle> = (0..n)
        .map(|i| Obstacle {
            center: [0.0, 200.0 + 30.0 * i as f32, 0.0],
            radius: 1.0,
        })
        .collect();
    // The wire list is a plain sequence, so any sequence of obstacles encodes a request.
    postcard::to_stdvec(&(
        base.needle,
        base.entry,
        base.target,
        obstacles,
        base.weights,
        base.options,
        base.driver,
        base.chance,
    ))
    .expect("a request encodes")
}

/// A scenario file written to the temporary folder for one test, removed when dropped.
pub struct TempScenario(pub PathBuf);

impl TempScenario {
    /// Writes `text` to a fresh file.
    pub fn new(text: &str) -> Self {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static N: AtomicUsize = AtomicUsize::new(0);
        let p = std::env::temp_dir().join(format!(
            "needle-e2e-scenario-{}-{}.toml",
            std::process::id(),
            N.fetch_add(1, Ordering::SeqCst)
        ));
        std::fs::write(&p, text).expect("write a temporary scenario");
        TempScenario(p)
    }
}

impl Drop for TempScenario {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Runs `needle` with `args` (the scenario file `text` replaces `{}`) and asserts it fails with
/// `expected` on stderr and without a panic.
pub fn needle_fails_with(text: &str, args: &[&str], expected: &str) {
    let f = TempScenario::new(text);
    let file = f.0.to_string_lossy().into_owned();
    let args: Vec<&str> = args
        .iter()
        .map(|a| if *a == "{}" { file.as_str() } else { a })
        .collect();
    let out = needle().args(&args).output().expect("run needle");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "needle {args:?} succeeded");
    assert!(err.contains(expected), "needle {args:?}: stderr: {err}");
    assert!(!err.contains("panicked"), "needle {args:?}: stderr: {err}");
}

/// Scenario `text` with `lines` added to its `[execution]` table (made when it has none):
/// TOML refuses a second table of the same name.
pub fn with_execution(text: &str, lines: &str) -> String {
    match text.find("[execution]\n") {
        Some(at) => {
            let end = at + "[execution]\n".len();
            format!("{}{lines}\n{}", &text[..end], &text[end..])
        }
        None => format!("{text}\n[execution]\n{lines}\n"),
    }
}

/// Scenario `text` with `planner.max_collision_probability = value` (a number, or `"off"`
/// quoted), in place of the one it has.
pub fn with_bound(text: &str, value: &str) -> String {
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("max_collision_probability"))
        .collect();
    let text = kept.join("\n") + "\n";
    let line = format!("max_collision_probability = {value}");
    if text.contains("[planner]\n") {
        text.replacen("[planner]\n", &format!("[planner]\n{line}\n"), 1)
    } else {
        format!("{text}\n[planner]\n{line}\n")
    }
}
