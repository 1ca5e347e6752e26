//! Flag values several commands read alike: counts of runs, scenarios and threads. A count of 0
//! or over the library's limit is a usage error (exit status 2), named by clap with the flag.

use needle_simulate::{MAX_RUNS, MAX_SCENARIOS};

/// A count of runs, 1 to [`MAX_RUNS`].
pub fn run_count(s: &str) -> Result<usize, String> {
    within(s, MAX_RUNS)
}

/// A count of scenarios, 1 to [`MAX_SCENARIOS`].
pub fn scenario_count(s: &str) -> Result<usize, String> {
    within(s, MAX_SCENARIOS)
}

/// A count from 1 to `max`.
fn within(s: &str, max: usize) -> Result<usize, String> {
    match at_least_one(s)? {
        n if n > max => Err(format!("must be at most {max}")),
        n => Ok(n),
    }
}

/// A count of at least one (`--threads 0` would run nothing, or silently one thread).
pub fn at_least_one(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}
