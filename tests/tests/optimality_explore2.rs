use needle_e2e::reference::random::random_scenario;
use needle_e2e::reference::{solve_form, Effort};

#[test]
#[ignore]
fn effort_convergence() {
    let n: u64 = std::env::var("N").ok().and_then(|v| v.parse().ok()).unwrap_or(10);
    let plane = std::env::var("SPACE").is_err();
    let hi: f64 = std::env::var("EFFORT").ok().and_then(|v| v.parse().ok()).unwrap_or(4.0);
    let mut worst = 0.0f64;
    for seed in 0..n {
        let s = random_scenario(seed, plane);
        for form in s.options.selected_forms().iter() {
            let a = solve_form(&s, form, Effort(1.0)).map(|r| r.objective);
            let b = solve_form(&s, form, Effort(hi)).map(|r| r.objective);
            let d = match (a, b) { (Some(a), Some(b)) => a - b, (None, None) => 0.0, _ => f64::INFINITY };
            worst = worst.max(d.abs());
            if d.abs() > 1e-6 { println!("seed {seed} {form}: effort1 {a:?} effort{hi} {b:?} diff {d}"); }
        }
    }
    println!("worst {worst}");
}
