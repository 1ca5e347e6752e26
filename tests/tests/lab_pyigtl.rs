//! The simulated lab's tracker read by an OpenIGTLink implementation nobody here wrote: pyigtl
//! (the venv `scripts/python-env` makes) connects to `hil-sim --lab` as Slicer connects to PLUS,
//! beside `needle steer`, and receives every pose `needle steer` used, with a good CRC.

mod lab_support;

use lab_support::{log_lines, temp_path, Lab};
use needle_e2e::{example, venv_python as python, workspace};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Duration;

#[test]
fn pyigtl_reads_the_lab_tracker_as_needle_steer_does() {
    let file = example("paper").to_str().unwrap().to_string();
    let lab = Lab::start(&file, 3, &[]);
    let port = lab.tracker.rsplit(':').next().unwrap().to_string();
    // Two frames a piece (target, tip); the paper insertion has more than 100 pieces.
    let frames = 200;
    let mut client = Command::new(python())
        .arg(workspace().join("igtl/tests/python/slicer_client.py"))
        .args([&port, &frames.to_string(), "30"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("start pyigtl");
    // pyigtl connects on a thread of its own: give it the time to be a client before the poses.
    std::thread::sleep(Duration::from_millis(1500));
    let log = temp_path("pyigtl.jsonl");
    let steered = lab.steer(&file, &["--log", log.to_str().unwrap()]);
    assert!(steered["steering"]["readings"].as_u64().unwrap() * 2 >= frames);
    let received: Vec<Value> = BufReader::new(client.stdout.take().unwrap())
        .lines()
        .map(|l| serde_json::from_str(&l.unwrap()).unwrap())
        .collect();
    assert!(client.wait().unwrap().success(), "pyigtl got every frame");
    assert_eq!(received.len() as u64, frames);
    let readings: Vec<Value> = log_lines(&log)
        .into_iter()
        .filter(|l| l["event"] == "reading")
        .collect();
    for (k, pair) in received.chunks(2).enumerate() {
        let (target, tip) = (&pair[0], &pair[1]);
        for (m, device) in [(target, "TargetToReference"), (tip, "NeedleTipToReference")] {
            assert_eq!(m["type"], "TRANSFORM", "{m}");
            assert_eq!(m["device"], device, "{m}");
            assert_eq!(m["crc_ok"], true, "{m}");
        }
        let used = &readings[k]["measurement"];
        let matrix = tip["matrix"].as_array().unwrap();
        for axis in 0..3 {
            let row = matrix[axis].as_array().unwrap();
            let at = |col: usize| row[col].as_f64().unwrap();
            let near = |a: f64, b: &Value| (a - b.as_f64().unwrap()).abs() < 1e-4;
            assert!(near(at(3), &used["pose"]["position"][axis]), "piece {k}");
            assert!(near(at(2), &used["pose"]["heading"][axis]), "piece {k}");
            assert!(near(at(1), &used["pose"]["bevel"][axis]), "piece {k}");
            let target = target["matrix"][axis][3].as_f64().unwrap();
            assert!(near(target, &used["target"][axis]), "piece {k}");
        }
    }
    let _ = std::fs::remove_file(log);
}
