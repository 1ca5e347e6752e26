//! One sphere budget for a whole scenario's anatomy: each segment starts at the cover its
//! tightness asks for, and while the scenario holds more spheres than the budget, the segment
//! whose next looser cover adds the least volume within the needle's reach per sphere saved is
//! loosened (a segment beyond the reach first: loosening it costs nothing a path can meet).

use super::cover::Candidate;
use anyhow::{bail, Result};

/// The cover chosen for each ladder (an index into its candidates, loosest first), so that the
/// spheres add up to at most `budget`. Each ladder's last candidate is the one asked for.
pub fn allocate(ladders: &[&[Candidate]], budget: usize) -> Result<Vec<usize>> {
    let mut at: Vec<usize> = ladders.iter().map(|l| l.len() - 1).collect();
    let count = |l: usize, i: usize| ladders[l][i].spheres.len();
    let mut total: usize = (0..ladders.len()).map(|l| count(l, at[l])).sum();
    while total > budget {
        // Per ladder, the next looser cover with fewer spheres, and what it costs a sphere.
        let step = |l: usize| {
            let now = count(l, at[l]);
            let i = (0..at[l]).rev().find(|&i| count(l, i) < now)?;
            let added = ladders[l][i].outside_in_reach_mm3 - ladders[l][at[l]].outside_in_reach_mm3;
            Some((added.max(0.0) / (now - count(l, i)) as f64, l, i))
        };
        let best = (0..ladders.len())
            .filter_map(step)
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let Some((_, l, i)) = best else {
            let least: usize = ladders
                .iter()
                .map(|l| l.iter().map(|c| c.spheres.len()).min().unwrap_or(0))
                .sum();
            bail!(
                "the anatomy needs at least {least} spheres, with each segment's loosest cover \
                 that keeps the entry and the target outside it, over the budget of {budget}: \
                 select fewer segments or free obstacles"
            );
        };
        total = total - count(l, at[l]) + count(l, i);
        at[l] = i;
    }
    Ok(at)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cover::Sphere;

    fn candidate(spheres: usize, outside: f64) -> Candidate {
        let s = Sphere {
            center: [0.0; 3],
            radius: 1.0,
        };
        Candidate {
            spheres: vec![s; spheres],
            tightness: None,
            outside_in_reach_mm3: outside,
            tight_enough: false,
        }
    }

    #[test]
    fn the_cheapest_spheres_are_saved_first() {
        // Ladder a saves 10 spheres for 100 mm³, b 10 for 10 mm³, c 10 for nothing.
        let a = [candidate(5, 200.0), candidate(15, 100.0)];
        let b = [candidate(5, 20.0), candidate(15, 10.0)];
        let c = [candidate(5, 0.0), candidate(15, 0.0)];
        let ladders: [&[Candidate]; 3] = [&a, &b, &c];
        assert_eq!(allocate(&ladders, 45).unwrap(), vec![1, 1, 1]);
        assert_eq!(allocate(&ladders, 40).unwrap(), vec![1, 1, 0]);
        assert_eq!(allocate(&ladders, 30).unwrap(), vec![1, 0, 0]);
        assert_eq!(allocate(&ladders, 15).unwrap(), vec![0, 0, 0]);
        let e = allocate(&ladders, 14).unwrap_err().to_string();
        assert!(
            e.contains("at least 15 spheres") && e.contains("budget of 14"),
            "{e}"
        );
    }

    #[test]
    fn a_looser_cover_with_as_many_spheres_is_skipped() {
        let a = [candidate(3, 90.0), candidate(8, 50.0), candidate(8, 10.0)];
        let ladders: [&[Candidate]; 1] = [&a];
        assert_eq!(allocate(&ladders, 7).unwrap(), vec![0]);
    }
}
