//! The README's promises, kept: every `needle` subcommand has an example in its command table,
//! every example there and in the first session runs as written (from a working directory that
//! sees the repository's `examples/` and `tests/`, the device commands against
//! `hil-sim --axes --tcp 127.0.0.1:7878` as the README starts it; `cargo xtask device-bench`'s, which
//! runs both boards in QEMU, is run by the firmware budgets test; `needle steer` against the
//! simulated lab the README starts), the plan tables it prints (the safe default's, then the paper's) are what `needle
//! plan` prints, and the scenario it shows plans.

mod wire_support;

use needle_e2e::readme::{fenced_blocks, table_examples, text as readme};
use needle_e2e::{needle_bin, workspace};
use std::path::{Path, PathBuf};
use std::process::Command;
use wire_support::SimProcess;

/// The address the README's device examples use.
const README_DEVICE: &str = "127.0.0.1:7878";

/// How the README starts the simulated lab its `needle steer` example steers, when it shows one.
const README_LAB: &str =
    "hil-sim --lab examples/paper.toml --tracker-port 18944 --robot-port 18945 &";

/// `needle`'s subcommands, as its help lists them.
fn subcommands() -> Vec<String> {
    let out = Command::new(needle_bin()).arg("--help").output().unwrap();
    let help = String::from_utf8(out.stdout).unwrap();
    help.split("Commands:")
        .nth(1)
        .and_then(|s| s.split("Options:").next())
        .expect("help lists commands")
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// A scratch working directory that sees the repository's examples and test data, so outputs
/// (plots) land there and not in the tree.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-readme-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for name in ["examples", "tests"] {
        std::os::unix::fs::symlink(workspace().join(name), dir.join(name)).unwrap();
    }
    dir
}

/// Runs one README line as written (`needle` is the binary under test); returns stdout.
fn run_example(line: &str, dir: &Path) -> String {
    let words: Vec<&str> = line.split_whitespace().collect();
    assert_eq!(words[0], "needle", "{line}");
    let out = Command::new(needle_bin())
        .args(&words[1..])
        .current_dir(dir)
        .output()
        .expect("run needle");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "`{line}` failed: {stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if words.contains(&"--json") {
        serde_json::from_str::<serde_json::Value>(&stdout)
            .unwrap_or_else(|e| panic!("`{line}` printed no JSON: {e}"));
    } else if !words.contains(&"ports") {
        let said = stdout.trim().len() + stderr.trim().len();
        assert!(said > 0, "`{line}` printed nothing");
    }
    for (i, w) in words.iter().enumerate() {
        let writes_svg = w.ends_with(".svg") && matches!(words[i - 1], "--plot" | "-o");
        if writes_svg {
            let svg = std::fs::read_to_string(dir.join(w)).expect("the plot was written");
            assert!(svg.starts_with("<svg"), "`{line}` wrote no SVG to {w}");
        }
    }
    stdout
}

/// Every example the README shows: its command table and the `needle` lines of its shell blocks.
fn every_example(text: &str) -> Vec<String> {
    let mut lines: Vec<String> = table_examples(text).into_iter().map(|(_, e)| e).collect();
    for (lang, block) in fenced_blocks(text) {
        for line in block.iter().filter(|_| lang == "sh") {
            let command = line.split('#').next().unwrap_or("").trim();
            if command.starts_with("needle ") {
                lines.push(command.to_string());
            }
        }
    }
    lines
}

#[test]
fn every_subcommand_has_an_example_in_the_command_table() {
    let text = readme();
    let documented: Vec<String> = table_examples(&text)
        .into_iter()
        .map(|(c, e)| {
            assert_eq!(e.split_whitespace().nth(1), Some(c.as_str()), "{e}");
            c
        })
        .collect();
    for command in subcommands() {
        assert!(
            documented.contains(&command),
            "README: no example of `needle {command}`"
        );
    }
}

#[test]
fn every_example_in_the_readme_runs_as_written() {
    let text = readme();
    let start = format!("hil-sim --axes --tcp {README_DEVICE} &");
    assert!(
        text.contains(&start),
        "the README starts hil-sim as {start}"
    );
    let _device = SimProcess::start(&["--axes", "--tcp", README_DEVICE]);
    let paper = workspace().join("examples/paper.toml");
    let _lab = text.contains(README_LAB).then(|| {
        let mut args: Vec<&str> = README_LAB.split_whitespace().skip(1).collect();
        args.pop(); // the shell's `&`
        args[1] = paper.to_str().unwrap();
        SimProcess::start(&args)
    });
    let dir = scratch("examples");
    let mut ran = 0;
    for line in every_example(&text) {
        run_example(&line, &dir);
        ran += 1;
    }
    assert!(ran >= subcommands().len(), "only {ran} examples ran");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_readme_plan_tables_are_what_plan_prints() {
    let blocks: Vec<Vec<String>> = fenced_blocks(&readme())
        .into_iter()
        .map(|(_, lines)| lines)
        .filter(|lines| {
            lines
                .first()
                .is_some_and(|l| l.starts_with("$ needle plan "))
        })
        .collect();
    let shown: Vec<&str> = blocks.iter().map(|b| b[0].as_str()).collect();
    // The safe default first, then the paper's optimum.
    assert_eq!(
        shown,
        [
            "$ needle plan examples/space.toml",
            "$ needle plan examples/paper.toml"
        ]
    );
    for block in &blocks {
        let command = block[0].trim_start_matches("$ ");
        let printed = run_example(command, &workspace());
        let printed: Vec<&str> = printed.lines().collect();
        assert!(block.len() > 10, "{command}: the table and the best plan");
        for (i, line) in block.iter().skip(1).enumerate() {
            assert_eq!(
                Some(&line.as_str()),
                printed.get(i),
                "README's line {i} of {command}"
            );
        }
    }
}

#[test]
fn the_readme_scenario_plans() {
    let text = readme();
    let toml: Vec<String> = fenced_blocks(&text)
        .into_iter()
        .filter(|(lang, _)| lang == "toml")
        .flat_map(|(_, lines)| lines)
        .collect();
    assert!(toml.len() > 5, "README shows a scenario");
    let dir = scratch("scenario");
    std::fs::write(dir.join("first.toml"), toml.join("\n")).unwrap();
    let out = run_example("needle plan first.toml --json", &dir);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["best"]["feasible"], true, "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}
