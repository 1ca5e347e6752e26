use super::*;
use crate::model::scenario::Obstacle;

fn form(word: &str) -> Form {
    Form::parse(word).unwrap()
}

/// The paper's scenario (entry at the origin along z, target 90 mm ahead) with no obstacles.
fn open_paper() -> Scenario {
    let mut s = Scenario::paper();
    s.obstacles.clear();
    s
}

#[test]
fn a_line_with_nothing_in_the_way_is_the_chord() {
    let s = open_paper();
    let out = solve_form(&s, form("L"), &[]);
    assert!(out.feasible);
    // L = 90 mm, D = 0 (no obstacles), F = a1 L + a4 N = 92.
    assert!((out.length - 90.0).abs() < 1e-3, "{}", out.length);
    assert!((out.objective - 92.0).abs() < 1e-3, "{}", out.objective);
    assert!(
        out.insertion.tilt_deg.abs() < 1e-2,
        "{}",
        out.insertion.tilt_deg
    );
    assert!(out.target_error < s.target.tolerance);
}

#[test]
fn a_line_through_an_obstacle_is_infeasible() {
    let mut s = open_paper();
    s.obstacles
        .push(Obstacle {
            center: [0.0, 0.0, 45.0],
            radius: 10.0,
        })
        .unwrap();
    let out = solve_form(&s, form("L"), &[]);
    assert!(!out.feasible);
    assert_eq!(out.status, SolveStatus::Infeasible);
    assert_eq!(out.objective, f32::INFINITY);
}

#[test]
fn a_form_with_an_extra_segment_is_no_worse_than_its_sub_form_plus_a4() {
    // With nothing in the way the straight line is optimal; one segment more can at best add a
    // segment of length zero: F = 92 + a4 = 94 exactly (no path is shorter than the chord).
    let s = open_paper();
    let line = solve_form(&s, form("L"), &[]);
    for word in ["LR", "RL"] {
        let out = solve_form(&s, form(word), core::slice::from_ref(&line));
        assert!(out.feasible, "{word}");
        assert!(
            (out.objective - 94.0).abs() < 1e-3,
            "{word}: {}",
            out.objective
        );
    }
    // Among the paper's obstacles, every two- and three-segment form against each of its
    // sub-forms.
    let s = Scenario::paper();
    let mut planned: heapless::Vec<FormOutcome, 8> = heapless::Vec::new();
    for word in ["R", "RL", "LR", "RR", "LRL", "RLR"] {
        let out = solve_form(&s, form(word), &planned);
        for sub in planned
            .iter()
            .filter(|o| o.feasible && o.form.len() + 1 == out.form.len())
        {
            let extended = (0..out.form.len()).any(|gap| {
                let rest = (0..out.form.len()).filter(|&i| i != gap);
                rest.map(|i| out.form.kind(i))
                    .eq((0..sub.form.len()).map(|i| sub.form.kind(i)))
            });
            if extended {
                let limit = sub.objective + s.weights.control;
                assert!(
                    out.objective <= limit + 1e-3,
                    "{word}: {} above {} + a4",
                    out.objective,
                    sub.objective
                );
            }
        }
        planned.push(out).unwrap();
    }
}

#[test]
fn shortlists_keep_the_lowest_distinct_points() {
    let at = |v: f32| {
        let mut x = [0.0; crate::optim::problem::MAX_VARS];
        x[0] = v;
        x
    };
    let mut items: heapless::Vec<(f32, Vars), SPACE_REFINED> = heapless::Vec::new();
    for (key, v) in [(5.0, 0.0), (3.0, 1.0), (4.0, 2.0)] {
        keep_best(items.as_mut_view(), 2, key, &at(v), 1);
    }
    // The limit is two: 5 made room for 4 (the last item takes the removed one's place).
    let keys: Vec<f32> = items.iter().map(|i| i.0).collect();
    assert_eq!(keys, [3.0, 4.0]);
    // A point within 0.2 of a kept one replaces it only when lower.
    keep_best(items.as_mut_view(), 2, 3.5, &at(1.1), 1);
    keep_best(items.as_mut_view(), 2, 2.0, &at(2.1), 1);
    let kept: Vec<(f32, f32)> = items.iter().map(|i| (i.0, i.1[0])).collect();
    assert_eq!(kept, [(3.0, 1.0), (2.0, 2.1)]);
    sort_by_objective(&mut items, |i| i.0);
    assert_eq!(items[0].0, 2.0);
    // Ties keep their order.
    let mut pairs = [(1.0, 'a'), (0.0, 'b'), (1.0, 'c'), (0.0, 'd')];
    sort_by_objective(&mut pairs, |p| p.0);
    assert_eq!(pairs.map(|p| p.1), ['b', 'd', 'a', 'c']);
}
