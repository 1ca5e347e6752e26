//! The scale bench: 256 spheres of which 32 lie within 20 mm of the entry–target segment
//! (`planner.risk = "sum"`, `planner.risk_within_mm = 20`), planned side by side with the same
//! 32 alone, on one thread, alternating. Prints both medians and their ratio (the goal: at most
//! 1.5), and fails unless the two plans are the same (forms, insertions and segments bit for
//! bit).
//!
//! `cargo run --release -p needle-cli --example scale_bench -- [RUNS] [SEED] [TOTAL] [NEAR]`
//! (default 15 runs, seed 1, 256 spheres, 32 near).

use needle_cli::scale::{near_and_far, plan_difference, NearFar};
use planner_core::plan;
use std::time::Instant;

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    let n = t.len();
    if n % 2 == 1 {
        t[n / 2]
    } else {
        (t[n / 2 - 1] + t[n / 2]) / 2.0
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, default: u64| -> Result<u64, Box<dyn std::error::Error>> {
        Ok(match std::env::args().nth(i) {
            Some(s) => s.parse()?,
            None => default,
        })
    };
    let runs = arg(1, 15)?.max(1) as usize;
    let seed = arg(2, 1)?;
    let total = arg(3, 256)? as usize;
    let near = arg(4, 32)? as usize;
    let NearFar { all, near_alone } = near_and_far(seed, total, near);
    let a = plan(&all)?;
    let b = plan(&near_alone)?;
    if let Some(d) = plan_difference(&a, &b) {
        return Err(format!("the plans differ: {d}").into());
    }
    let (mut t_all, mut t_near) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        for (s, times) in [(&all, &mut t_all), (&near_alone, &mut t_near)] {
            let t = Instant::now();
            let r = plan(s)?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(&r);
        }
    }
    let (m_all, m_near) = (median(t_all), median(t_near));
    let best = a
        .best()
        .map(|o| o.form.to_string())
        .unwrap_or("none".into());
    println!("seed {seed}: {total} spheres, {near} within 20 mm; same plan (best {best})");
    println!("{total} spheres: median {m_all:.2} ms over {runs} runs");
    println!("{near} alone:   median {m_near:.2} ms over {runs} runs");
    println!("ratio {:.3} (goal <= 1.5)", m_all / m_near);
    Ok(())
}
