//! Bad scenarios and flags get a message that says what is wrong and what is allowed, and never
//! a plan of something other than what was written.

use needle_e2e::{example, needle_fails_with};

fn paper() -> String {
    std::fs::read_to_string(example("paper")).unwrap()
}

#[test]
fn lists_of_the_wrong_length_are_refused() {
    let text = paper().replace(
        "center = [0.0, 30.0, 50.0]",
        "center = [0.0, 30.0, 50.0, 1.0]",
    );
    needle_fails_with(&text, &["plan", "{}"], "expected exactly 3 numbers");
    let text = paper().replace("position = [0.0, 0.0, 90.0]", "position = [0.0, 90.0]");
    needle_fails_with(&text, &["plan", "{}"], "expected exactly 3 numbers");
}

#[test]
fn messages_say_which_input_and_what_is_allowed() {
    let text = paper().replace("penalty = 1000.0", "penalty = -1");
    needle_fails_with(
        &text,
        &["plan", "{}"],
        "weights.penalty is out of range: allowed is 0 or more",
    );
    let text = paper().replace("max_tilt_deg = 60.0", "max_tilt_deg = 90.0");
    needle_fails_with(&text, &["plan", "{}"], "0 to 89 degrees");
    let text = paper().replace("tolerance = 0.1", "tolerance = 90");
    needle_fails_with(
        &text,
        &["plan", "{}"],
        "within target.tolerance of the entry point",
    );
    let text = paper().replace("tolerance = 0.1", "tolerance = 1e-9");
    needle_fails_with(&text, &["plan", "{}"], "use at least 0.000172 mm");
    let text = paper().replace("position = [0.0, 0.0, 90.0]", "position = [0.0, 0.0, 1e12]");
    needle_fails_with(&text, &["plan", "{}"], "within 1000 mm of the origin");
    // The paper's radius typed in metres would otherwise plan a 0.02 mm "arc".
    let text = paper().replace("curvature_radius = 63.7", "curvature_radius = 0.0637");
    needle_fails_with(
        &text,
        &["plan", "{}"],
        "needle.curvature_radius is out of range: allowed is 5 to 1000 mm",
    );
}

#[test]
fn form_selections_that_select_nothing_say_why() {
    needle_fails_with(
        &paper(),
        &["plan", "{}", "--forms", "RLRL", "--max-degree", "2"],
        "no form of --forms RLRL has a degree within --max-degree 2",
    );
    let text = paper().replace("[planner]", "[planner]\nforms = []");
    needle_fails_with(&text, &["plan", "{}"], "planner.forms is empty");
}

#[test]
fn the_rrt_takes_no_form_flags_it_would_ignore() {
    for flag in [["--max-degree", "2"], ["--forms", "RL"]] {
        let args = [&["rrt", "{}"][..], &flag[..]].concat();
        needle_fails_with(&paper(), &args, "unexpected argument");
    }
}

#[test]
fn a_reader_that_closes_the_pipe_early_ends_the_command_quietly() {
    use std::io::Read;
    use std::process::Stdio;
    // Megabytes of JSON, far more than a pipe buffers: the writes after the reader left fail.
    let mut child = needle_e2e::needle()
        .args(["simulate", example("paper").to_str().unwrap()])
        .args(["--runs", "400", "--detail", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 16];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "status {:?}, stderr: {err}",
        out.status
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(first.starts_with(b"{\"runs\":400"));
}

#[test]
fn counts_of_work_have_an_upper_bound_named_in_the_error() {
    // Each of these once reached an allocation of the count asked and aborted the process.
    let huge = "1000000000000";
    needle_fails_with(
        &paper(),
        &["simulate", "{}", "--runs", huge],
        "at most 1000000 runs",
    );
    needle_fails_with(
        &paper(),
        &["benchmark", "--runs", huge],
        "must be at most 1000000",
    );
    needle_fails_with(
        &paper(),
        &["benchmark", "--scenarios", huge],
        "must be at most 100000",
    );
    needle_fails_with(
        &paper(),
        &[
            "sweep", "{}", "--weight", "risk", "--from", "0", "--to", "1", "--steps", huge,
        ],
        "it must be 1 to 10000",
    );
}

/// The firmware's measurement is a checkout's developer task now: `needle device-bench` says
/// where it went, with the arguments given, and exits 1 (help included).
#[test]
fn device_bench_points_at_the_xtask() {
    for args in [
        &["device-bench", "--check", "--json"][..],
        &["device-bench", "--help"][..],
        &["device-bench"][..],
    ] {
        let out = needle_e2e::needle()
            .args(args)
            .output()
            .expect("run needle");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "needle {args:?}: {err}");
        let expected = format!("run `cargo xtask {}`", args.join(" "));
        assert!(err.contains(&expected), "needle {args:?}: {err}");
        assert!(out.stdout.is_empty(), "needle {args:?} printed to stdout");
    }
    let help = needle_e2e::needle()
        .arg("--help")
        .output()
        .expect("run needle");
    assert!(!String::from_utf8_lossy(&help.stdout).contains("device-bench"));
}
