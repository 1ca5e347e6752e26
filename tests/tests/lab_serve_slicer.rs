//! 3D Slicer as a client of `needle steer --serve-slicer`, played by pyigtl (an OpenIGTLink
//! implementation nobody here wrote). Its own test binary: run beside the other pyigtl test, two
//! labs, two pythons and two steering programs on two cores made a lab's tracker late enough to
//! trip its interlock.

mod lab_support;

use lab_support::Lab;
use needle_e2e::{example, venv_python as python, workspace};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

/// Slicer as a client of `needle steer --serve-slicer`, as its OpenIGTLinkIF connector of type
/// Client connects to PLUS: pyigtl connects and receives the plan `POLYDATA`, the obstacles (as
/// fiducials, and as a `POLYDATA` model of spheres), the `STATUS` and `STRING` of the state and
/// the estimated tip's `TRANSFORM`s, every CRC good.
#[test]
fn pyigtl_as_slicer_connects_to_needle_steer_and_sees_the_insertion() {
    let file = example("paper").to_str().unwrap().to_string();
    let lab = Lab::start(&file, 4, &[]);
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .unwrap()
        .port()
        .to_string();
    let count = 11;
    let mut client = Command::new(python())
        .arg(workspace().join("igtl/tests/python/slicer_client.py"))
        .args([&port, &count.to_string(), "60"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("start pyigtl");
    // Viewing is under test here, not the interlocks: a loaded machine must not trip them.
    let args = [
        "--serve-slicer",
        &port,
        "--wait-for-slicer",
        "30",
        "--tracking-timeout-ms",
        "5000",
    ];
    let steered = lab.steer(&file, &args);
    assert_eq!(steered["stop_reason"], Value::Null, "{steered}");
    let received: Vec<Value> = BufReader::new(client.stdout.take().unwrap())
        .lines()
        .map(|l| serde_json::from_str(&l.unwrap()).unwrap())
        .collect();
    assert!(client.wait().unwrap().success(), "pyigtl got {received:?}");
    assert_eq!(received.len(), count);
    for m in &received {
        assert_eq!(m["crc_ok"], true, "{m}");
        assert_eq!(m["error"], Value::Null, "{m}");
    }
    let kinds: Vec<(&str, &str)> = received
        .iter()
        .map(|m| (m["type"].as_str().unwrap(), m["device"].as_str().unwrap()))
        .collect();
    assert_eq!(
        kinds[..5],
        [
            ("POLYDATA", "NeedlePlan"),
            ("POINT", "NeedleObstacles"),
            ("POLYDATA", "NeedleObstaclesModel"),
            ("STATUS", "NeedleSteering"),
            ("STRING", "NeedleSteering"),
        ]
    );
    assert!(
        kinds[5..].contains(&("TRANSFORM", "NeedleTipEstimate")),
        "{kinds:?}"
    );
    let plan = &received[0];
    assert_eq!(plan["repacked_identical"], true);
    assert!(plan["points"].as_array().unwrap().len() > 50);
    spheres_as_pyigtl_reads_them(&received[2]);
    assert_eq!(received[3]["text"], "steering");
    assert_eq!(received[4]["string"], "steering");
}

/// The obstacles' model as pyigtl unpacked it (and packed it back to the same bytes): the
/// paper's three obstacles, each 42 points at one distance from their centre, 80 triangles on
/// them, no lines.
fn spheres_as_pyigtl_reads_them(model: &Value) {
    assert_eq!(model["repacked_identical"], true, "{model}");
    assert_eq!(model["lines"], serde_json::json!([]));
    let points: Vec<[f64; 3]> = model["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| [0, 1, 2].map(|i| p[i].as_f64().unwrap()))
        .collect();
    let polygons = model["polygons"].as_array().unwrap();
    assert_eq!((points.len(), polygons.len()), (3 * 42, 3 * 80));
    for (k, polygon) in polygons.iter().enumerate() {
        let sphere = k / 80;
        let indices: Vec<u64> = polygon
            .as_array()
            .unwrap()
            .iter()
            .map(|i| i.as_u64().unwrap())
            .collect();
        assert_eq!(indices.len(), 3, "a triangle");
        let on = (42 * sphere as u64)..(42 * (sphere as u64 + 1));
        assert!(indices.iter().all(|i| on.contains(i)), "{indices:?}");
    }
    for sphere in points.chunks(42) {
        let c = [0, 1, 2].map(|i| sphere.iter().map(|p| p[i]).sum::<f64>() / 42.0);
        let d: Vec<f64> = sphere
            .iter()
            .map(|p| (0..3).map(|i| (p[i] - c[i]).powi(2)).sum::<f64>().sqrt())
            .collect();
        let (lo, hi) = d
            .iter()
            .fold((f64::MAX, 0.0_f64), |(l, h), &x| (l.min(x), h.max(x)));
        assert!(lo > 0.0 && hi - lo < 1e-3 * hi, "a sphere: {lo} to {hi}");
    }
}
