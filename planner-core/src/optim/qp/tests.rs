//! The QP on small problems whose optima are known in closed form.

use super::*;

fn identity(n: usize) -> [Vars; MAX_VARS] {
    let mut h = [[0.0; MAX_VARS]; MAX_VARS];
    for (i, row) in h.iter_mut().enumerate().take(n) {
        row[i] = 1.0;
    }
    h
}

fn vars(values: &[f32]) -> Vars {
    let mut v = [0.0; MAX_VARS];
    v[..values.len()].copy_from_slice(values);
    v
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-5
}

#[test]
fn unconstrained_step_is_newton() {
    let s = Qp::new(2, identity(2), vars(&[2.0, -4.0])).solve().unwrap();
    assert!(close(s.p[0], -2.0) && close(s.p[1], 4.0));
}

#[test]
fn equality_constrained_optimum_and_its_multiplier() {
    // min ½|p|² - p0 - 2 p1  subject to  p0 - p1 = 0: p = (1.5, 1.5); stationarity
    // p + g = λ a gives λ = p0 - 1 = 0.5.
    let mut qp = Qp::new(2, identity(2), vars(&[-1.0, -2.0]));
    qp.push_eq(&vars(&[1.0, -1.0]));
    let s = qp.solve().unwrap();
    assert!(close(s.p[0], 1.5) && close(s.p[1], 1.5), "{:?}", &s.p[..2]);
    assert!(close(s.eq_mult[0], 0.5), "{}", s.eq_mult[0]);
}

#[test]
fn bound_and_equality_are_respected() {
    // min ½|p|² + g·p with g = (-1, -1, 0), p0 + p1 + p2 = 0, p0 ≤ 0.25.
    let mut qp = Qp::new(3, identity(3), vars(&[-1.0, -1.0]));
    qp.push_eq(&vars(&[1.0, 1.0, 1.0]));
    qp.push_row(&vars(&[-1.0]), -0.25);
    let s = qp.solve().unwrap();
    // Without the bound: p = (1/3, 1/3, -2/3); with it p0 = 0.25 and, minimising
    // ½(p1² + (0.25 + p1)²) - p1, p1 = 0.375, p2 = -0.625.
    assert!(close(s.p[0], 0.25), "{:?}", &s.p[..3]);
    assert!(close(s.p[1], 0.375) && close(s.p[2], -0.625));
    assert!(s.mult[0] > 0.0);
}

#[test]
fn an_active_axis_bound_stops_the_step_and_carries_the_multiplier() {
    // min ½|p|² - 2 p0 - p1 with p0 ≤ 0.5 (the row -e0 ≥ -0.5): p = (0.5, 1), multiplier 1.5.
    let mut qp = Qp::new(2, identity(2), vars(&[-2.0, -1.0]));
    qp.push_axis(0, -1.0, -0.5);
    qp.push_axis(1, -1.0, -3.0);
    let s = qp.solve().unwrap();
    assert!(close(s.p[0], 0.5) && close(s.p[1], 1.0), "{:?}", &s.p[..2]);
    assert!(close(s.mult[0], 1.5), "{}", s.mult[0]);
    assert_eq!(s.mult[1], 0.0, "the inactive bound has no multiplier");
}

#[test]
fn an_inactive_inequality_leaves_the_newton_step_alone() {
    // The row p0 + p1 ≥ -10 does not bind the Newton step (-1, 2).
    let mut qp = Qp::new(2, identity(2), vars(&[1.0, -2.0]));
    qp.push_row(&vars(&[1.0, 1.0]), -10.0);
    let s = qp.solve().unwrap();
    assert!(close(s.p[0], -1.0) && close(s.p[1], 2.0));
    assert_eq!(s.mult[0], 0.0);
}

#[test]
fn a_general_row_and_an_axis_row_of_the_same_vector_give_the_same_step() {
    let h = identity(2);
    let g = vars(&[-2.0, -1.0]);
    let mut general = Qp::new(2, h, g);
    general.push_row(&vars(&[0.0, -1.0]), -0.25);
    let mut axis = Qp::new(2, h, g);
    axis.push_axis(1, -1.0, -0.25);
    let (a, b) = (general.solve().unwrap(), axis.solve().unwrap());
    assert_eq!(a.p, b.p);
    assert_eq!(a.mult[0], b.mult[0]);
}

#[test]
fn a_positive_right_hand_side_is_clamped_so_that_zero_stays_feasible() {
    // p0 ≥ 1 would exclude p = 0, which the QP starts from: it becomes p0 ≥ 0. With the
    // gradient pushing p0 down, the row binds at 0.
    let mut qp = Qp::new(1, identity(1), vars(&[1.0]));
    qp.push_axis(0, 1.0, 1.0);
    let s = qp.solve().unwrap();
    assert_eq!(s.p[0], 0.0);
    assert!(close(s.mult[0], 1.0));
}

#[test]
fn dependent_equality_rows_are_reported_singular() {
    // p = 0 satisfies every row the QP can hold, so it is never infeasible: what it cannot
    // solve are dependent rows, whose KKT matrix is singular.
    let mut qp = Qp::new(2, identity(2), vars(&[1.0, 1.0]));
    qp.push_eq(&vars(&[1.0, 1.0]));
    qp.push_eq(&vars(&[2.0, 2.0]));
    assert_eq!(qp.solve().unwrap_err(), QpError::Singular);
}

#[test]
fn a_direction_of_unbounded_descent_is_reported_not_followed() {
    // No curvature along p1 and a gradient along it: within the box |p1| ≤ 1 the minimiser is
    // p1 = 1, but the first KKT system (empty working set) is singular and the QP says so
    // instead of returning a step.
    let mut h = identity(2);
    h[1][1] = 0.0;
    let mut qp = Qp::new(2, h, vars(&[0.0, -1.0]));
    qp.push_axis(1, 1.0, -1.0);
    qp.push_axis(1, -1.0, -1.0);
    assert_eq!(qp.solve().unwrap_err(), QpError::Singular);
}

#[test]
fn rows_beyond_the_capacity_are_refused() {
    let mut qp = Qp::new(1, identity(1), vars(&[1.0]));
    let mut pushed = 0;
    while qp.push_axis(0, 1.0, -1.0) {
        pushed += 1;
    }
    assert_eq!(pushed, MAX_ROWS);
    assert!(!qp.push_row(&vars(&[1.0]), -1.0));
    assert!(!qp.push_axis(MAX_VARS, 1.0, -1.0));
}
