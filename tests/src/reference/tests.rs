//! Unit tests of the reference planner against closed forms and the paper's figures.

use super::*;
use planner_core::form::catalogue;

fn paper_table(effort: f64) -> Vec<(Form, Option<RefSolution>)> {
    let s = Scenario::paper();
    catalogue()
        .into_iter()
        .filter(|f| f.len() <= 3)
        .map(|f| (f, solve_form(&s, f, Effort(effort))))
        .collect()
}

#[test]
fn print_paper_table() {
    let t0 = std::time::Instant::now();
    for (f, sol) in paper_table(1.0) {
        match sol {
            Some(s) => println!("{s} evals={}", s.evaluations),
            None => println!("{f}: infeasible"),
        }
    }
    println!("{:?}", t0.elapsed());
}
