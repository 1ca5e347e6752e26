//! What the SQP remembers of one problem between its runs: the local solutions found, and the
//! iterates of the runs that reached them. A run that comes within a basin of a remembered point
//! no better than itself stops there: its descent would follow the earlier run to a solution
//! already known.

use crate::optim::problem::Vars;

/// Distance (largest change of any variable) within which an iterate counts as in the basin of a
/// known point. 0.05 (was 0.03): 2.8 % fewer host instructions on the paper plan, the
/// optimality suites unchanged (docs/optimality.md), plans within 2.2e-5 in F.
pub const BASIN: f32 = 0.05;

/// Largest final step of a run whose end marks a basin.
pub const STATIONARY: f32 = 1e-3;

/// Entries of a [`Known`] that iterates leave free for the solutions themselves.
pub const ROOM_FOR_SOLUTIONS: usize = 8;

/// Points remembered for one problem (variables, objective); its capacity is the caller's.
pub type Known = heapless::vec::VecView<(Vars, f32)>;

/// The memory of one problem during one run: the points known before the run, then the run's
/// own accepted iterates (which its own stop test leaves out: a descent passes its own trail).
pub struct Memory<'a> {
    known: &'a mut Known,
    before: usize,
}

impl<'a> Memory<'a> {
    /// A run starts with what `known` holds.
    pub fn start(known: &'a mut Known) -> Self {
        let before = known.len();
        Memory { known, before }
    }

    /// Whether `x` (objective `f`, `n` variables) lies within [`BASIN`] of a point known before
    /// this run that is no worse.
    pub fn holds(&self, x: &Vars, f: f32, n: usize) -> bool {
        self.known
            .iter()
            .take(self.before)
            .any(|(k, kf)| f >= *kf && near(x, k, n))
    }

    /// The run accepted the iterate `x` (objective `f`): kept while room is left for solutions.
    pub fn passed(&mut self, x: &Vars, f: f32) {
        if self.known.len() + ROOM_FOR_SOLUTIONS < self.known.capacity() {
            // Room was checked.
            let _ = self.known.push((*x, f));
        }
    }

    /// The run ended where it marks no basin (not stationary, or no start): its iterates are
    /// forgotten.
    pub fn forget(self) {
        self.known.truncate(self.before);
    }

    /// The run ended stationary at `x` (objective `f`): its iterates more than a basin away from
    /// `x` are kept, and `x` itself when no kept point lies in its basin and there is room.
    pub fn settle(self, x: &Vars, f: f32, n: usize) {
        let mut kept = self.before;
        for i in self.before..self.known.len() {
            if let Some(&entry) = self.known.get(i) {
                if !near(&entry.0, x, n) {
                    if let Some(slot) = self.known.get_mut(kept) {
                        *slot = entry;
                    }
                    kept += 1;
                }
            }
        }
        self.known.truncate(kept);
        if !self.known.iter().any(|(k, _)| near(k, x, n)) {
            // Full: the solution is simply not remembered.
            let _ = self.known.push((*x, f));
        }
    }
}

/// Whether every one of the first `n` variables of `a` and `b` differ by less than [`BASIN`].
fn near(a: &Vars, b: &Vars, n: usize) -> bool {
    (0..n).all(|j| libm::fabsf(a[j] - b[j]) < BASIN)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::problem::MAX_VARS;

    fn at(v: f32) -> Vars {
        [v; MAX_VARS]
    }

    #[test]
    fn a_run_is_not_stopped_by_its_own_trail_and_forgets_it_unless_stationary() {
        let mut store: heapless::Vec<(Vars, f32), 16> = heapless::Vec::new();
        let _ = store.push((at(0.0), 1.0));
        let mut m = Memory::start(store.as_mut_view());
        m.passed(&at(1.0), 5.0);
        // Its own iterate, same objective: not a reason to stop.
        assert!(!m.holds(&at(1.01), 5.0, 3));
        // The point known before: no worse than 1.0, so a point near it at 2.0 stops.
        assert!(m.holds(&at(0.01), 2.0, 3));
        assert!(!m.holds(&at(0.01), 0.5, 3), "a better point is not stopped");
        assert!(!m.holds(&at(0.2), 2.0, 3), "outside the basin");
        m.forget();
        assert_eq!(store.len(), 1);
    }

    #[test]
    fn a_stationary_run_keeps_its_far_iterates_and_its_solution() {
        let mut store: heapless::Vec<(Vars, f32), 16> = heapless::Vec::new();
        let mut m = Memory::start(store.as_mut_view());
        m.passed(&at(1.0), 5.0);
        m.passed(&at(0.51), 4.0);
        m.passed(&at(0.52), 3.0); // within a basin of the end: redundant
        m.settle(&at(0.5), 2.0, 3);
        assert_eq!(store.len(), 2);
        assert_eq!((store[0].1, store[1].1), (5.0, 2.0));
        // A later run passing near the first iterate stops there.
        let m = Memory::start(store.as_mut_view());
        assert!(m.holds(&at(1.02), 6.0, 3));
    }

    #[test]
    fn iterates_leave_room_for_solutions() {
        let mut store: heapless::Vec<(Vars, f32), 12> = heapless::Vec::new();
        let mut m = Memory::start(store.as_mut_view());
        for k in 0..12 {
            m.passed(&at(k as f32), 100.0 - k as f32);
        }
        assert_eq!(store.len(), 12 - ROOM_FOR_SOLUTIONS);
        let m = Memory::start(store.as_mut_view());
        m.settle(&at(50.0), 1.0, 3);
        assert_eq!(store.last().map(|e| e.1), Some(1.0));
    }

    #[test]
    fn a_run_from_a_point_of_an_earlier_descent_stops_there() {
        use crate::optim::problem::Problem;
        use crate::optim::sqp;
        use crate::search::{solve::solve_form, starts::extension_starts};
        use crate::{Form, Scenario};
        let s = Scenario::paper();
        let (short, form) = (Form::parse("RL").unwrap(), Form::parse("LRL").unwrap());
        let previous = [solve_form(&s, short, &[])];
        let starts = extension_starts(&s, form, &previous);
        let mut checked = 0;
        // Turned away from the shorter form's optimum, so that the descent is long.
        let turned = starts.iter().flat_map(|(sides, x)| {
            [-0.3f32, -0.15, 0.15, 0.3].map(|d| {
                let mut x = *x;
                x[0] += d;
                (*sides, x)
            })
        });
        for (sides, x0) in turned {
            let p = Problem::new(&s, form, sides);
            let mut store: heapless::Vec<(Vars, f32), 24> = heapless::Vec::new();
            let Ok(first) = sqp::solve(&p, &x0, store.as_mut_view()) else {
                continue;
            };
            // The run's iterates far from its end come first, then its solution.
            let Some(&(on_the_way, f)) = store.first().filter(|_| store.len() >= 2) else {
                continue;
            };
            assert!(f > first.eval.objective);
            let again = sqp::solve(&p, &on_the_way, store.as_mut_view()).unwrap();
            assert_eq!((again.iterations, again.step_norm), (1, 0.0));
            assert_eq!(again.status, crate::SolveStatus::KnownBasin);
            assert!(again.eval.objective >= first.eval.objective);
            let mut empty: heapless::Vec<(Vars, f32), 24> = heapless::Vec::new();
            let alone = sqp::solve(&p, &on_the_way, empty.as_mut_view()).unwrap();
            assert!(alone.iterations > 1, "without the memory the run descends");
            checked += 1;
        }
        assert!(checked > 0, "no start whose descent left a trail");
    }
}
