//! Weight robustness on the paper's scenario (its Figures 6-8 and Table 2), through
//! `needle sweep --json`, and the parallel sweep giving the same points as a serial one.

use needle_analysis::sweep::{self, Range, Weight};
use needle_e2e::{needle, needle_json};
use planner_core::Scenario;
use serde_json::Value;

fn sweep_json(args: &[&str]) -> Value {
    needle_json(&[&["sweep", "examples/paper.toml", "--json"], args].concat())
}

fn best(p: &Value) -> (String, f64, f64) {
    let b = &p["best"];
    (
        b["form"].as_str().unwrap_or("-").to_string(),
        b["length"].as_f64().unwrap_or(f64::NAN),
        b["objective"].as_f64().unwrap_or(f64::NAN),
    )
}

#[test]
fn risk_sweep_keeps_rl_with_length_rising_slowly() {
    let v = sweep_json(&[
        "--weight",
        "risk",
        "--from",
        "1",
        "--to",
        "10",
        "--steps",
        "10",
        "--max-degree",
        "2",
    ]);
    assert_eq!(v["weight"], "risk");
    let points = v["points"].as_array().unwrap();
    assert_eq!(points.len(), 10);
    let mut lengths = Vec::new();
    for (k, p) in points.iter().enumerate() {
        assert!((p["value"].as_f64().unwrap() - (k + 1) as f64).abs() < 1e-9);
        let (form, length, _) = best(p);
        assert_eq!(form, "RL", "at risk weight {}", k + 1);
        assert!(p["best"]["risk"].as_f64().unwrap() > 0.0);
        let forms = p["forms"].as_array().unwrap();
        assert_eq!(forms.len(), 5, "N <= 2: R, L, RR, RL, LR");
        for f in forms {
            assert!(f["form"].is_string() && f["feasible"].is_boolean());
            assert_eq!(f["objective"].is_number(), f["feasible"] == true);
        }
        lengths.push(length);
    }
    // A safer path costs length, but little: never shorter, under 3 % longer over the range.
    for w in lengths.windows(2) {
        assert!(w[1] >= w[0] - 0.05, "{lengths:?}");
    }
    assert!(lengths[9] > lengths[0], "{lengths:?}");
    assert!(lengths[9] < lengths[0] * 1.03, "{lengths:?}");
}

#[test]
fn penalty_sweep_changes_nothing() {
    let v = sweep_json(&[
        "--weight",
        "penalty",
        "--from",
        "1",
        "--to",
        "1e9",
        "--steps",
        "10",
        "--log",
        "--max-degree",
        "2",
    ]);
    let points = v["points"].as_array().unwrap();
    assert_eq!(points.len(), 10);
    assert_eq!(points[9]["value"].as_f64().unwrap(), 1e9);
    let first = best(&points[0]);
    assert_eq!(first.0, "RL");
    for p in points {
        // Bit for bit: H is zero on every feasible path, so a3 cannot move the optimum.
        assert_eq!(best(p), first);
        assert_eq!(p["forms"], points[0]["forms"]);
    }
}

#[test]
fn control_sweep_switches_forms_as_table_2() {
    let v = sweep_json(&[
        "--weight",
        "control",
        "--from",
        "0",
        "--to",
        "10",
        "--steps",
        "21",
        "--max-degree",
        "3",
    ]);
    let forms: Vec<(f64, String)> = v["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["value"].as_f64().unwrap(), best(p).0))
        .collect();
    let at = |w: f64| &forms.iter().find(|(v, _)| (v - w).abs() < 1e-9).unwrap().1;
    assert_eq!(at(0.0).len(), 3, "a 3-segment form at a4 = 0: {forms:?}");
    assert_eq!(at(10.0), "R", "{forms:?}");
    // RL over one contiguous middle range that contains 1..7.
    let rl: Vec<f64> = forms
        .iter()
        .filter(|(_, f)| f == "RL")
        .map(|(v, _)| *v)
        .collect();
    let (lo, hi) = (rl[0], rl[rl.len() - 1]);
    assert!(lo <= 1.0 && hi >= 7.0, "{forms:?}");
    assert!(forms
        .iter()
        .filter(|(v, _)| *v >= lo && *v <= hi)
        .all(|(_, f)| f == "RL"));
    // The control degree never rises with a4.
    let degrees: Vec<usize> = forms.iter().map(|(_, f)| f.len()).collect();
    assert!(degrees.windows(2).all(|w| w[1] <= w[0]), "{forms:?}");
}

#[test]
fn parallel_sweep_equals_serial_sweep() {
    let s = Scenario::paper();
    let range = Range {
        from: 0.0,
        to: 10.0,
        steps: 8,
        log: false,
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let one = sweep::run(&s, Weight::Control, &range, 1, || {}).unwrap();
    let two = sweep::run(&s, Weight::Control, &range, 2, || {
        done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(done.into_inner(), 8);
    assert_eq!(
        sweep::to_json(Weight::Control, &one),
        sweep::to_json(Weight::Control, &two)
    );
    let csv = sweep::to_csv(Weight::Control, &one);
    assert_eq!(csv.lines().count(), 9);
    assert!(csv.starts_with("control,best_form,control_degree,length,risk,objective,F_R,F_L,"));
}

#[test]
fn sweep_rejects_bad_ranges_clearly() {
    for (args, msg) in [
        (
            vec!["--weight", "risk", "--from", "0", "--to", "10", "--log"],
            "above zero",
        ),
        (
            vec!["--weight", "risk", "--from=-1", "--to", "10"],
            "negative",
        ),
        (
            vec![
                "--weight", "risk", "--from", "1", "--to", "2", "--steps", "0",
            ],
            "it must be 1 to 10000",
        ),
        (
            vec!["--weight", "speed", "--from", "1", "--to", "2"],
            "possible values: length, risk, penalty, control",
        ),
    ] {
        let out = needle()
            .args(["sweep", "examples/paper.toml"])
            .args(&args)
            .output()
            .unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(msg), "{args:?}: {err}");
    }
}
