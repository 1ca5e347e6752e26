//! Bad tracker frames in `needle steer`, each counted and reported (JSON `rejected_frames`, a
//! `rejected` line in the insertion log naming the error) and read past without costing a
//! reading: a corrupted CRC, a wrong body size, a 20-byte device name that is not UTF-8, a
//! non-rigid matrix. A 20-byte name without a terminator is valid (the default tip name is one):
//! the one letter off the tip's is ignored and counted (`ignored_frames`).

mod lab_support;

use lab_support::{log_lines, simulated, temp_path, Lab};
use needle_e2e::{example, needle};

#[test]
fn bad_frames_are_counted_logged_and_read_past() {
    let file = example("paper").to_str().unwrap().to_string();
    let expected = simulated(&file, 3, 1)[0].clone();
    let log = temp_path("bad-frames.jsonl");
    let mut lab = Lab::start(&file, 3, &["--bad-frames-every", "5"]);
    let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
    let truth = lab.next_run();
    assert_eq!(truth["target_error"], expected["target_error"], "no cost");
    assert_eq!(v["steering"], expected["steering"]);
    // One bad frame before every 5th piece's pose, the five kinds in turn.
    let bad = truth["pieces"].as_u64().unwrap() / 5;
    let ignored = bad / 5;
    assert_eq!(v["rejected_frames"], bad - ignored, "{v}");
    assert_eq!(v["ignored_frames"], ignored, "{v}");
    assert_eq!(
        "NeedleTipToReference".len(),
        20,
        "the tip's own name fills the field, unterminated, and every pose of it was used"
    );
    assert_eq!(truth["pieces"], v["steering"]["readings"]);
    let lines = log_lines(&log);
    let errors: Vec<&str> = lines
        .iter()
        .filter(|l| l["event"] == "rejected")
        .map(|l| l["error"].as_str().unwrap())
        .collect();
    assert_eq!(errors.len() as u64, bad - ignored);
    for (i, e) in errors.iter().enumerate() {
        let kind = ["BadCrc", "BadBodySize", "NotUtf8", "NotRigid"][i % 4];
        assert_eq!(*e, kind, "rejection {i}: {errors:?}");
    }
    let stop = lines.last().unwrap();
    assert_eq!(stop["rejected_frames"], v["rejected_frames"]);
    assert_eq!(stop["ignored_frames"], v["ignored_frames"]);
    let _ = std::fs::remove_file(log);
}

/// A device name no frame can carry (over 20 bytes) is refused before anything starts.
#[test]
fn a_name_over_20_bytes_is_refused() {
    let out = needle()
        .args(["steer", example("paper").to_str().unwrap()])
        .args(["--tracker", "127.0.0.1:1", "--robot", "127.0.0.1:1"])
        .args(["--tip-name", "NeedleTipToReference2"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--tip-name") && err.contains("1 to 20 bytes"),
        "{err}"
    );
}
