//! The benchmark's pooled figures, checked by hand.

use super::*;

fn pool(runs: usize, open: &[f32], arrived: &[f32], stops: usize) -> Pool {
    Pool {
        runs,
        open_errors: open.to_vec(),
        open_hits: 1,
        arrived_errors: arrived.to_vec(),
        stops: BTreeMap::from([("no_safe_continuation", stops)]),
        // Of the arrived runs, those within 1 mm reached, the rest missed.
        outcomes: BTreeMap::from([
            ("reached", arrived.iter().filter(|e| **e <= 1.0).count()),
            ("missed", arrived.iter().filter(|e| **e > 1.0).count()),
            ("collided", 0),
            ("stopped", stops),
        ]),
        closed_hits: 0,
        closed_runs: runs,
        within_reach: runs - stops,
        reached_within_reach: arrived.len().min(runs - stops),
    }
}

#[test]
fn totals_pool_the_runs() {
    let mut all = pool(2, &[1.0, 3.0], &[0.5], 1);
    all.merge(&pool(4, &[2.0; 4], &[1.0, 1.0, 1.0, 4.0], 0));
    let (o, c) = (all.open(), all.closed().unwrap());
    assert_eq!((all.runs, o.hits), (6, 2));
    assert_eq!(o.mean_target_error, 2.0);
    assert!((o.hit_percent - 100.0 / 3.0).abs() < 1e-12);
    assert_eq!((c.arrived, c.stops, c.hits), (5, 1, 0));
    // The 4 mm arrival is a miss, not a reach.
    assert_eq!((c.reached, c.missed, c.collided, c.stopped), (4, 1, 0, 1));
    assert!((c.reached_percent - 400.0 / 6.0).abs() < 1e-12);
    assert_eq!((c.within_reach, c.reached_within_reach), (5, 5));
    assert_eq!(c.mean_target_error, Some(1.5));
    assert_eq!(c.p95_target_error, Some(4.0));
    let none = pool(3, &[1.0; 3], &[], 3).closed().unwrap();
    let open_only = Pool {
        closed_runs: 0,
        ..pool(3, &[1.0; 3], &[], 0)
    };
    assert_eq!(open_only.closed(), None);
    assert_eq!((none.reached_percent, none.mean_target_error), (0.0, None));
}
