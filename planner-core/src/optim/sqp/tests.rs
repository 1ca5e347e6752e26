//! The SQP on problems whose outcome is known: every exit status reached, and the residual that
//! tells a converged run from one stopped early.

use super::*;
use crate::model::scenario::{Obstacle, Workspace};
use crate::search::{solve::solve_form, starts::extension_starts};
use crate::{Form, Scenario};

fn vars(values: &[f32]) -> Vars {
    let mut v = [0.0; MAX_VARS];
    v[..values.len()].copy_from_slice(values);
    v
}

fn with_obstacles(mut s: Scenario, target: [f32; 3], obstacles: &[([f32; 3], f32)]) -> Scenario {
    s.target.position = target;
    s.obstacles.clear();
    for &(center, radius) in obstacles {
        s.obstacles.push(Obstacle { center, radius }).unwrap();
    }
    s
}

/// The paper's RL from the first start the search derives from its R, turned away from it so
/// that the descent takes several iterations.
fn paper_rl_start(s: &Scenario) -> (Problem<'_>, Vars) {
    let form = Form::parse("RL").unwrap();
    let previous = [solve_form(s, Form::parse("R").unwrap(), &[])];
    let (sides, mut x0) = extension_starts(s, form, &previous)[0];
    x0[0] += 0.3;
    (Problem::new(s, form, sides), x0)
}

#[test]
fn a_converged_run_has_a_small_residual_and_one_stopped_by_its_budget_a_large_one() {
    let s = Scenario::paper();
    let (p, x0) = paper_rl_start(&s);
    let done = solve_within(&p, &x0, MAX_ITERATIONS).unwrap();
    assert_eq!(done.status, SolveStatus::Converged);
    assert!(done.iterations > 1);
    let early = solve_within(&p, &x0, 2).unwrap();
    assert_eq!(
        (early.status, early.iterations),
        (SolveStatus::BudgetExhausted, 2)
    );
    assert!(early.eval.objective > done.eval.objective);
    // The objective's gradient is of the order of the arc radius (63.7 mm per radius-length):
    // converged, the Lagrangian's is below 1 % of that; two iterations in, it is not.
    assert!(
        done.kkt_residual < 0.5 && early.kkt_residual > 10.0 * done.kkt_residual,
        "converged {}, after one iteration {}",
        done.kkt_residual,
        early.kkt_residual
    );
}

#[test]
fn a_line_search_that_finds_no_decrease_stops_with_its_own_status() {
    // A plane scenario where the first QP step of this RR start runs into the obstacle above the
    // target at every trial length: the run stops there, far from stationary.
    let s = with_obstacles(
        Scenario::paper(),
        [0.0, 0.36587334, 63.872246],
        &[
            ([0.0, 23.263653, 71.70918], 7.7258644),
            ([0.0, 3.3696823, 74.7224], 10.879915),
            ([0.0, 8.908115, 62.599453], 6.9780183),
        ],
    );
    let p = Problem::new(&s, Form::parse("RR").unwrap(), 0);
    let sol = solve_within(&p, &vars(&[0.5194421, 1.0503403, 0.0]), MAX_ITERATIONS).unwrap();
    assert_eq!(
        (sol.status, sol.iterations),
        (SolveStatus::LineSearchStalled, 1)
    );
    assert!(sol.kkt_residual > 1.0, "{}", sol.kkt_residual);
}

#[test]
fn a_qp_that_cannot_be_solved_ends_the_run_with_its_own_status() {
    // RRL in 3-D started as a bare line (both arcs of zero length): the tangent QP's KKT system
    // is singular however it is retried. No QP was solved, so the residual is the objective's
    // gradient alone.
    let mut s = with_obstacles(
        Scenario::paper(),
        [-19.652344, -23.859554, 85.55348],
        &[
            ([-26.526989, -16.860886, 27.60855], 5.982321),
            ([21.24826, -12.868866, 30.385092], 3.4281774),
            ([-8.216555, -23.980474, 37.802032], 2.3903217),
        ],
    );
    s.options.workspace = Workspace::Space;
    let p = Problem::new(&s, Form::parse("RRL").unwrap(), 0);
    let x0 = vars(&[0.27197418, -0.21775636, 0.0, 0.0, 1.4280444, 0.0, 0.0]);
    let sol = solve_within(&p, &x0, MAX_ITERATIONS).unwrap();
    assert_eq!((sol.status, sol.iterations), (SolveStatus::QpFailed, 1));
    let d = p.derivatives(&sol.eval);
    let gradient = d.grad[..p.n].iter().fold(0.0f32, |m, g| m.max(g.abs()));
    assert_eq!(sol.kkt_residual, gradient);
}

#[test]
fn a_start_that_cannot_reach_the_target_is_an_error() {
    // One arc of at most 10 degrees cannot bend onto a target 90 mm ahead and 0 mm aside.
    let mut s = Scenario::paper();
    s.needle.max_arc_deg = 10.0;
    s.target.position = [0.0, 30.0, 90.0];
    let p = Problem::new(&s, Form::parse("R").unwrap(), 0);
    let err = solve_within(&p, &vars(&[0.0, 0.1]), MAX_ITERATIONS).unwrap_err();
    assert_eq!(err, SolveFailure::StartOffTarget);
}

#[test]
fn a_start_through_an_obstacle_is_an_error() {
    // The paper's straight line to the target passes through its middle obstacle.
    let s = Scenario::paper();
    let p = Problem::new(&s, Form::parse("L").unwrap(), 0);
    let err = solve_within(&p, &vars(&[0.0, 90.0 / 63.7]), MAX_ITERATIONS).unwrap_err();
    assert_eq!(err, SolveFailure::StartInadmissible);
}

#[test]
fn a_stationary_run_is_remembered_and_a_later_one_stops_in_its_basin() {
    let s = Scenario::paper();
    let (p, x0) = paper_rl_start(&s);
    let mut store: heapless::Vec<(Vars, f32), 24> = heapless::Vec::new();
    let first = solve(&p, &x0, store.as_mut_view()).unwrap();
    assert_eq!(first.status, SolveStatus::Converged);
    let again = solve(&p, &first.eval.x, store.as_mut_view()).unwrap();
    assert_eq!(
        (again.status, again.iterations),
        (SolveStatus::KnownBasin, 1)
    );
    assert_eq!(again.step_norm, 0.0);
}
