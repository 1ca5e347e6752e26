//! A tracker and a robot written from docs/lab.md alone, not from hil-sim
//! (tests/lab_support/doc_lab.py: pyigtl's messages, kinematics of its own, a needle curving 5 %
//! less than planned, a free-running 40 Hz tracker with 0.05 mm of noise, pieces taking a fiftieth
//! of their planned durations, the base starting at another roll): `needle steer` reaches the
//! target of paper and space insertions, on poses sampled after their pieces ended.

mod lab_support;

use lab_support::{log_lines, temp_path};
use needle_e2e::{example, needle, venv_python as python, workspace};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdout, Command, Stdio};

/// The lab of doc_lab.py as a process, killed when dropped.
struct DocLab {
    child: Child,
    tracker: String,
    robot: String,
    runs: BufReader<ChildStdout>,
}

impl DocLab {
    fn start(file: &str, extra: &[&str]) -> DocLab {
        let mut child = Command::new(python())
            .arg(workspace().join("tests/tests/lab_support/doc_lab.py"))
            .arg(file)
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start doc_lab.py");
        let mut runs = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        runs.read_line(&mut line).unwrap();
        let words: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(words.len(), 4, "{line}");
        DocLab {
            tracker: words[1].to_string(),
            robot: words[3].to_string(),
            child,
            runs,
        }
    }
}

impl Drop for DocLab {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn insertions(name: &str, runs: usize, extra: &[&str]) {
    let file = example(name).to_str().unwrap().to_string();
    let mut lab = DocLab::start(&file, extra);
    for i in 0..runs {
        let log = temp_path(&format!("doc-{name}-{i}.jsonl"));
        let out = needle()
            .args([
                "steer",
                &file,
                "--tracker",
                &lab.tracker,
                "--robot",
                &lab.robot,
            ])
            .args(["--json", "--log", log.to_str().unwrap()])
            .output()
            .unwrap();
        let v: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
        let mut line = String::new();
        lab.runs.read_line(&mut line).unwrap();
        let truth: Value = serde_json::from_str(&line).unwrap();
        let what = format!("{name} {extra:?} insertion {i}: {v} {truth}");
        assert_eq!(out.status.code(), Some(0), "{what}");
        assert_eq!(v["outcome"], "reached", "{what}");
        let miss = truth["target_error"].as_f64().unwrap();
        assert!(miss < 0.5, "{what}");
        for r in log_lines(&log).iter().filter(|l| l["event"] == "reading") {
            let sampled = r["pose_sampled_s"].as_f64().unwrap();
            let ended = r["piece_ended_s"].as_f64().unwrap();
            assert!(sampled >= ended, "{what}: {r}");
        }
        println!(
            "{name} {extra:?}: true miss {miss:.3} mm, {} readings, reaction {}, pose age {}",
            v["steering"]["readings"], v["reaction_ms"], v["pose_age_ms"]
        );
        let _ = std::fs::remove_file(log);
    }
}

#[test]
fn paper_from_the_docs_alone() {
    insertions("paper", 5, &["--seed", "1"]);
    insertions("paper", 5, &["--seed", "2", "--start-roll", "37"]);
}

#[test]
fn space_from_the_docs_alone() {
    insertions("space", 5, &["--seed", "3"]);
    insertions("space", 5, &["--seed", "4", "--start-roll", "-200"]);
}
