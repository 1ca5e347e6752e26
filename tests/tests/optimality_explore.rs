//! A debugging aid: the reference optimum of one form of one random scenario, with timing.
//! `SEED=3 FORM=RL [SPACE=1] [EFFORT=4] cargo test -p needle-e2e --test optimality_explore -- --ignored --nocapture`

use needle_e2e::reference::random::random_scenario;
use needle_e2e::reference::{solve_form, Effort};
use planner_core::Form;

#[test]
#[ignore]
fn one() {
    let seed: u64 = std::env::var("SEED").unwrap().parse().unwrap();
    let plane = std::env::var("SPACE").is_err();
    let form = Form::parse(&std::env::var("FORM").unwrap()).unwrap();
    let effort: f64 = std::env::var("EFFORT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1.0);
    let t = std::time::Instant::now();
    let s = random_scenario(seed, plane);
    println!(
        "{:?}",
        solve_form(&s, form, Effort(effort)).map(|r| r.to_string())
    );
    println!("{:?}", t.elapsed());
}
