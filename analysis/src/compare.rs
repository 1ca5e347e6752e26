//! The optimiser against the RRT baseline (the paper's Table 4): length, D, N, F, target error and
//! time of the optimiser's best path and of RRT paths over several seeds (median and spread).

use super::parallel;
use super::pieces::Segment;
use super::rrt::{self, Outcome, RrtError};
use needle_report::json::{write_sorted, SegmentJson};
use planner_core::{PlanError, PlanReport, Scenario};
use serde::Serialize;
use std::fmt;
use std::time::Instant;

/// One row of the comparison; in a report, a value that is not finite is written as `null`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Row {
    /// L (mm).
    pub length: f64,
    /// D.
    pub risk: f64,
    /// N.
    pub control_degree: f64,
    /// F.
    pub objective: f64,
    /// Distance from the path's end to the target (mm).
    pub target_error: f64,
    /// Wall-clock time (µs).
    pub time_us: f64,
}

impl Row {
    fn from_rrt(o: &Outcome) -> Row {
        Row {
            length: f64::from(o.score.length),
            risk: f64::from(o.score.risk),
            control_degree: o.score.control_degree as f64,
            objective: f64::from(o.score.objective),
            target_error: f64::from(o.score.target_error),
            time_us: o.time_us as f64,
        }
    }

    fn map(rows: &[Row], pick: impl Fn(&[f64]) -> f64) -> Row {
        let col = |f: fn(&Row) -> f64| pick(&rows.iter().map(f).collect::<Vec<_>>());
        Row {
            length: col(|r| r.length),
            risk: col(|r| r.risk),
            control_degree: col(|r| r.control_degree),
            objective: col(|r| r.objective),
            target_error: col(|r| r.target_error),
            time_us: col(|r| r.time_us),
        }
    }
}

/// Median of the values (mean of the middle two for an even count); NaN when empty.
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}

/// The comparison's results.
#[derive(Debug)]
pub struct Comparison {
    /// The optimiser's plan and its time.
    pub optimizer: Result<(PlanReport, u64), PlanError>,
    /// Each RRT run with its seed.
    pub runs: Vec<(u64, Result<Outcome, RrtError>)>,
}

impl Comparison {
    /// The optimiser's row.
    pub fn optimizer_row(&self) -> Option<Row> {
        let (report, time_us) = self.optimizer.as_ref().ok()?;
        let b = report.best()?;
        Some(Row {
            length: f64::from(b.length),
            risk: f64::from(b.risk),
            control_degree: b.form.len() as f64,
            objective: f64::from(b.objective),
            target_error: f64::from(b.target_error),
            time_us: *time_us as f64,
        })
    }

    /// Rows of the RRT runs that found a path.
    pub fn rrt_rows(&self) -> Vec<Row> {
        self.runs
            .iter()
            .filter_map(|(_, r)| r.as_ref().ok().map(Row::from_rrt))
            .collect()
    }

    /// Column-wise median of the successful RRT runs.
    pub fn rrt_median(&self) -> Option<Row> {
        let rows = self.rrt_rows();
        (!rows.is_empty()).then(|| Row::map(&rows, median))
    }

    /// Column-wise minimum and maximum of the successful RRT runs.
    pub fn rrt_spread(&self) -> Option<(Row, Row)> {
        let rows = self.rrt_rows();
        let lo = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (!rows.is_empty()).then(|| (Row::map(&rows, lo), Row::map(&rows, hi)))
    }
}

/// Plans with the optimiser, then runs the RRT with `seeds` (in parallel on `threads` threads).
pub fn run(
    scenario: &Scenario,
    options: &rrt::Options,
    seeds: &[u64],
    threads: usize,
    done: impl Fn() + Sync,
) -> Comparison {
    let clock = Instant::now();
    let optimizer = planner_core::plan(scenario).map(|r| (r, clock.elapsed().as_micros() as u64));
    done();
    // One RRT per thread at a time: each run's time is then a single-core time like the optimiser's.
    let runs = parallel::map(
        seeds,
        threads,
        |&seed| (seed, rrt::run(scenario, &rrt::Options { seed, ..*options })),
        done,
    );
    Comparison { optimizer, runs }
}

/// The `needle compare --json` object (written only: nothing reads it back).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComparisonJson {
    /// The optimiser's best path, or why there is none.
    pub optimizer: OptimizerJson,
    /// The RRT runs and their statistics.
    pub rrt: RrtRunsJson,
}

/// `optimizer`: the best path's row and form, or why there is none.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum OptimizerJson {
    /// The optimiser planned.
    Planned {
        /// The best path's figures.
        #[serde(flatten)]
        row: Row,
        /// The best form.
        form: String,
    },
    /// It did not.
    Failed {
        /// Why.
        error: String,
    },
}

/// `rrt`: the runs, how many found a path, and column-wise median, minimum and maximum.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RrtRunsJson {
    /// Median of the runs that found a path, `null` if none did.
    pub median: Option<Row>,
    /// `min` and `max`, present when a run found a path.
    #[serde(flatten)]
    pub spread: Option<SpreadJson>,
    /// Runs that found a path.
    pub found: usize,
    /// Every run, by seed.
    pub runs: Vec<RunJson>,
}

/// Column-wise extremes of the runs that found a path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpreadJson {
    /// Column-wise minimum.
    pub min: Row,
    /// Column-wise maximum.
    pub max: Row,
}

/// One RRT run: its row, effort and segments, or why it found no path.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum RunJson {
    /// The run found a path.
    Found {
        /// The run's seed.
        seed: u64,
        /// The path's figures.
        #[serde(flatten)]
        row: Row,
        /// Nodes grown.
        nodes: usize,
        /// Samples drawn.
        iterations: usize,
        /// The merged segments.
        segments: Vec<SegmentJson>,
    },
    /// It ran out of samples, or its options were wrong.
    Failed {
        /// The run's seed.
        seed: u64,
        /// Why.
        error: String,
    },
}

impl RunJson {
    fn new(seed: u64, run: &Result<Outcome, RrtError>) -> RunJson {
        match run {
            Ok(o) => RunJson::Found {
                seed,
                row: Row::from_rrt(o),
                nodes: o.tree.len(),
                iterations: o.iterations,
                segments: o.segments.iter().map(Segment::to_json).collect(),
            },
            Err(e) => RunJson::Failed {
                seed,
                error: e.to_string(),
            },
        }
    }
}

/// The `needle compare --json` report of `c`.
pub fn to_json(c: &Comparison) -> ComparisonJson {
    let optimizer = match (&c.optimizer, c.optimizer_row()) {
        (Ok((report, _)), Some(row)) => OptimizerJson::Planned {
            row,
            form: report
                .best()
                .map(|b| b.form.to_string())
                .unwrap_or_default(),
        },
        (Err(e), _) => OptimizerJson::Failed {
            error: e.to_string(),
        },
        (Ok(_), None) => OptimizerJson::Failed {
            error: "no best form".to_string(),
        },
    };
    ComparisonJson {
        optimizer,
        rrt: RrtRunsJson {
            median: c.rrt_median(),
            spread: c
                .rrt_spread()
                .map(|(lo, hi)| SpreadJson { min: lo, max: hi }),
            found: c.rrt_rows().len(),
            runs: c
                .runs
                .iter()
                .map(|(seed, r)| RunJson::new(*seed, r))
                .collect(),
        },
    }
}

impl fmt::Display for ComparisonJson {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_sorted(self, f)
    }
}

/// The side-by-side table printed by `needle compare`.
pub fn to_table(c: &Comparison) -> String {
    let mut s = format!(
        "{:<18} {:>9} {:>8} {:>4} {:>9} {:>13} {:>12}\n",
        "", "L (mm)", "D", "N", "F", "target (mm)", "time (ms)"
    );
    let row = |name: &str, r: &Row| {
        format!(
            "{:<18} {:>9.2} {:>8.4} {:>4} {:>9.3} {:>13.4} {:>12.3}\n",
            name,
            r.length,
            r.risk,
            r.control_degree,
            r.objective,
            r.target_error,
            r.time_us / 1000.0
        )
    };
    match (&c.optimizer, c.optimizer_row()) {
        (Ok((report, _)), Some(r)) => {
            let form = report
                .best()
                .map(|b| b.form.to_string())
                .unwrap_or_default();
            s.push_str(&row(&format!("optimiser ({form})"), &r));
        }
        (Err(e), _) => s.push_str(&format!("{:<18} no plan: {e}\n", "optimiser")),
        (Ok(_), None) => s.push_str(&format!("{:<18} no plan\n", "optimiser")),
    }
    let found = c.rrt_rows().len();
    match (c.rrt_median(), c.rrt_spread()) {
        (Some(m), Some((lo, hi))) => {
            s.push_str(&row("RRT median", &m));
            s.push_str(&row("RRT min", &lo));
            s.push_str(&row("RRT max", &hi));
        }
        _ => s.push_str(&format!("{:<18} no run found a path\n", "RRT")),
    }
    s.push_str(&format!(
        "RRT: {found} of {} seeds found a path; each stops within its tolerance of the target, \
         so its target error is not zero (columns are medians/extremes taken separately)\n",
        c.runs.len()
    ));
    for (seed, r) in &c.runs {
        if let Err(e) = r {
            s.push_str(&format!("  seed {seed}: {e}\n"));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(super::median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(super::median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(super::median(&[]).is_nan());
    }
}
