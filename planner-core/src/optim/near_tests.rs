//! The near set and the reach of the risk term: what the optimiser keeps per obstacle with more
//! obstacles than slots, and what D counts.

use super::objective::MAX_NEAR;
use super::problem::{Problem, MAX_VARS};
use crate::model::form::Form;
use crate::model::scenario::{Obstacle, RiskMeasure, Scenario, Workspace};

/// 40 spheres round the entry–target line at growing distances (index i at 6 + i mm from the
/// axis), so the 32 nearest of any path near the axis are most of the first ones.
fn crowded(count: usize) -> Scenario {
    let mut s = Scenario::paper();
    s.options.workspace = Workspace::Space;
    s.options.risk = RiskMeasure::Sum;
    s.target.position = [0.0, 0.0, 90.0];
    s.obstacles.clear();
    for i in 0..count {
        let turn = i as f32 * 2.4;
        let out = 6.0 + i as f32;
        s.obstacles
            .push(Obstacle {
                center: [
                    out * turn.cos(),
                    out * turn.sin(),
                    20.0 + (i % 7) as f32 * 8.0,
                ],
                radius: 2.0,
            })
            .unwrap();
    }
    s
}

fn point(p: &Problem) -> [f32; MAX_VARS] {
    let mut x = [0.0; MAX_VARS];
    x[0] = 0.05;
    x[1] = -0.03;
    for i in 0..p.form.len() {
        x[p.length_var(i)] = 0.4 + 0.1 * i as f32;
    }
    x
}

#[test]
fn the_near_set_holds_the_nearest_in_index_order_and_d_counts_every_obstacle() {
    let s = crowded(40);
    let p = Problem::new(&s, Form::parse("RL").unwrap(), 0);
    let v = p.value(&point(&p));
    assert_eq!(v.near_count, MAX_NEAR);
    let near = &v.near[..MAX_NEAR];
    assert!(near.windows(2).all(|w| w[0] < w[1]), "{near:?}");
    // Every obstacle left out is at least as far as every one kept.
    let farthest_kept = v.clearance[..MAX_NEAR]
        .iter()
        .fold(0.0f32, |m, &d| m.max(d));
    let mut all = crowded(40);
    let mut left_out = 0;
    for o in 0..40 {
        if v.slot_of(o).is_none() {
            all.obstacles.clear();
            all.obstacles.push(s.obstacles[o]).unwrap();
            let alone = Problem::new(&all, p.form, 0).value(&v.x);
            assert!(alone.clearance[0] >= farthest_kept, "obstacle {o}");
            left_out += 1;
        }
    }
    assert_eq!(left_out, 40 - MAX_NEAR);
    // D is the sum over all 40: the objective less L and N.
    let w = &s.weights;
    let d = (v.objective - w.length * v.geo.total_length() - w.control * 2.0) / w.risk;
    let mut sum = 0.0f32;
    for o in 0..40 {
        all.obstacles.clear();
        all.obstacles.push(s.obstacles[o]).unwrap();
        sum += 1.0 / Problem::new(&all, p.form, 0).value(&v.x).clearance[0];
    }
    assert!((d - sum).abs() < 1e-4 * sum, "{d} vs {sum}");
}

#[test]
fn the_gradient_of_d_sums_every_obstacle_beyond_the_slots() {
    // Weighted up so that the 8 obstacles outside the slots move the gradient well past the
    // tolerance of the finite differences; a reach of 50 mm takes in all 40.
    for reach in [None, Some(12.0), Some(50.0)] {
        let mut s = crowded(40);
        s.options.risk_within_mm = reach;
        s.weights.risk = 200.0;
        let p = Problem::new(&s, Form::parse("RL").unwrap(), 0);
        let x = point(&p);
        let e = p.derivatives(&p.value(&x));
        let h = 1e-3f32;
        for k in 0..p.n {
            let (mut xp, mut xm) = (x, x);
            xp[k] += h;
            xm[k] -= h;
            let fd = (p.value(&xp).objective - p.value(&xm).objective) / (2.0 * h);
            assert!(
                (fd - e.grad[k]).abs() < 3e-2 * (1.0 + fd.abs()),
                "reach {reach:?} var {k}: {fd} vs {}",
                e.grad[k]
            );
        }
    }
}

#[test]
fn beyond_the_reach_an_obstacle_adds_nothing_and_d_is_continuous() {
    let mut s = crowded(10);
    let form = Form::parse("RL").unwrap();
    let x = point(&Problem::new(&s, form, 0));
    let base = Problem::new(&s, form, 0).value(&x);
    let reach = 10.0;
    s.options.risk_within_mm = Some(reach);
    let p = Problem::new(&s, form, 0);
    let v = p.value(&x);
    let w = &s.weights;
    let d = (v.objective - w.length * v.geo.total_length() - w.control * 2.0) / w.risk;
    let mut want = 0.0f32;
    let mut beyond = 0;
    for &c in &base.clearance[..base.near_count] {
        if c < reach {
            want += 1.0 / c - 1.0 / reach;
        } else {
            beyond += 1;
        }
    }
    assert!(beyond > 0 && beyond < 10, "{beyond} beyond the reach");
    assert!((d - want).abs() < 1e-4 * (1.0 + want), "{d} vs {want}");
    // Only those within the reach take slots (and so rows).
    assert_eq!(v.near_count, 10 - beyond);
    assert!(v.clearance[..v.near_count].iter().all(|&c| c < reach));
}
