use needle_e2e::reference::compare::{compare_scenario, describe_scenario, Ask};
use needle_e2e::reference::random::random_scenario;
use needle_e2e::reference::Effort;
use planner_core::Scenario;

#[test]
#[ignore]
fn explore() {
    let n: u64 = std::env::var("N").ok().and_then(|v| v.parse().ok()).unwrap_or(10);
    let start: u64 = std::env::var("START").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
    let plane = std::env::var("SPACE").is_err();
    let effort: f64 = std::env::var("EFFORT").ok().and_then(|v| v.parse().ok()).unwrap_or(1.0);
    let mut scenarios = vec![("paper".to_string(), Scenario::paper())];
    for seed in start..start + n {
        scenarios.push((format!("seed {seed}"), random_scenario(seed, plane)));
    }
    let mut bad = 0;
    for (name, s) in scenarios {
        let t = std::time::Instant::now();
        let rep = compare_scenario(&s, Effort(effort), Ask::AllForms);
        println!("== {name} ({:?}) err={:?}", t.elapsed(), rep.plan_error);
        let mut printed = false;
        for (o, r, c) in &rep.forms {
            let tag = c.mismatch.as_ref().map_or("ok".to_string(), |m| format!("{m:?}"));
            let diff = r.as_ref().map(|r| f64::from(o.objective) - r.objective);
            println!("  {} {tag}: planner F={} ref F={:?} diff={:?}", o.form, o.objective, r.as_ref().map(|r| r.objective), diff);
            if c.mismatch.is_some() || diff.is_some_and(|d| d.abs() > 0.01) {
                if !printed { println!("{}", describe_scenario(&s)); printed = true; }
                println!("{}", c.detail);
            }
            if c.mismatch.is_some() { bad += 1; }
        }
    }
    println!("mismatches: {bad}");
}
