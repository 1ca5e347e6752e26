//! Plans do not drift: `needle plan --json` of the examples and of five random scenarios equals,
//! number for number, what main printed when they were last blessed (tests/data/golden/*.plan.json;
//! first before the restructuring, last when `kkt_residual` became the first-order residual at
//! the reported path, which moved that key only). A change that moves plan bits on purpose
//! re-blesses them with `GOLDEN_BLESS=1 cargo test -p needle-e2e --test golden_plans` and says
//! what moved and by how much F moved, in docs/optimality.md.
//!
//! Every key of the stored output must come back with exactly the same value; keys added later
//! (new outputs) are allowed, and `stats.time_us` is a measurement, so it is not compared.

use needle_e2e::{example, needle, needle_json, workspace};
use serde_json::Value;
use std::path::PathBuf;

fn golden(name: &str) -> PathBuf {
    workspace().join("tests/data/golden").join(name)
}

/// Every difference between `stored` and `now` below `path`, as readable lines.
fn differences(path: &str, stored: &Value, now: &Value, out: &mut Vec<String>) {
    if path == "stats.time_us" {
        return;
    }
    match (stored, now) {
        (Value::Object(a), Value::Object(b)) => {
            for (key, va) in a {
                let sub = if path.is_empty() {
                    key.clone()
                } else {
                    format!("{path}.{key}")
                };
                match b.get(key) {
                    Some(vb) => differences(&sub, va, vb, out),
                    None => out.push(format!("{sub}: missing now")),
                }
            }
        }
        (Value::Array(a), Value::Array(b)) => {
            if a.len() != b.len() {
                out.push(format!("{path}: {} entries, now {}", a.len(), b.len()));
                return;
            }
            for (i, (va, vb)) in a.iter().zip(b).enumerate() {
                differences(&format!("{path}[{i}]"), va, vb, out);
            }
        }
        // Numbers compare as f64 bit patterns: f32 results print exactly, so any change shows.
        (Value::Number(a), Value::Number(b))
            if a.as_f64().map(f64::to_bits) != b.as_f64().map(f64::to_bits) =>
        {
            out.push(format!("{path}: {a} before, {b} now"));
        }
        // Equal bit patterns are equal, whether written as an integer or not.
        (Value::Number(_), Value::Number(_)) => {}
        (a, b) if a != b => out.push(format!("{path}: {a} before, {b} now")),
        _ => {}
    }
}

fn assert_unchanged(scenario: PathBuf, stored: &str) {
    let args = ["plan", scenario.to_str().unwrap(), "--json"];
    if std::env::var_os("GOLDEN_BLESS").is_some() {
        // needle's own text: serde_json does not round-trip every float it parses.
        let out = needle().args(args).output().expect("run needle");
        assert!(out.status.success(), "needle {args:?}");
        std::fs::write(golden(stored), out.stdout).expect("golden output written");
        return;
    }
    let now = needle_json(&args);
    let text = std::fs::read_to_string(golden(stored)).expect("golden output");
    let before: Value = serde_json::from_str(&text).expect("golden JSON");
    let mut diff = Vec::new();
    differences("", &before, &now, &mut diff);
    assert!(
        diff.is_empty(),
        "{stored}: {} differences, first: {:#?}",
        diff.len(),
        &diff[..diff.len().min(12)]
    );
}

#[test]
fn example_plans_are_unchanged() {
    assert_unchanged(example("paper"), "paper.plan.json");
    assert_unchanged(example("space"), "space.plan.json");
}

#[test]
fn random_scenario_plans_are_unchanged() {
    for k in 1..=5 {
        assert_unchanged(
            golden(&format!("random-{k}.toml")),
            &format!("random-{k}.plan.json"),
        );
    }
}

#[test]
fn the_comparison_sees_a_one_ulp_change() {
    let a: Value =
        serde_json::json!({"best": {"objective": 96.2216796875_f64}, "stats": {"time_us": 1}});
    let b: Value = serde_json::json!({"best": {"objective": f64::from_bits(96.2216796875_f64.to_bits() + 1)}, "stats": {"time_us": 2}});
    let mut diff = Vec::new();
    differences("", &a, &b, &mut diff);
    assert_eq!(diff.len(), 1, "{diff:?}");
    diff.clear();
    differences("", &a, &a, &mut diff);
    assert!(diff.is_empty());
}
