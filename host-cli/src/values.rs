//! Flag values several commands read alike: counts of runs, scenarios and threads, and how
//! polygons become circles. A count of 0 or over the library's limit is a usage error (exit
//! status 2), named by clap with the flag.

use needle_scenario::approx::Method;
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

/// How a polygon becomes circles (`needle_scenario::approx::Method`); `circle` and `edged` are
/// accepted as older names.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// One smallest enclosing circle: regular, compact obstacles.
    #[value(alias = "circle")]
    Circumscribed,
    /// A few circles over slabs of the polygon: irregular obstacles without deep notches.
    Segmented,
    /// Small circles along the outline: very irregular or thin obstacles.
    #[value(alias = "edged")]
    Bordered,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::Circumscribed => Method::Circumscribed,
            MethodArg::Segmented => Method::Segmented,
            MethodArg::Bordered => Method::Bordered,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    /// The command line reads every name and older name of a method as a scenario file does.
    #[test]
    fn the_flags_name_every_method_as_the_library() {
        let flags: Vec<Method> = MethodArg::value_variants()
            .iter()
            .map(|&m| m.into())
            .collect();
        assert_eq!(flags, Method::ALL);
        for m in Method::ALL {
            for name in [Some(m.name()), m.older_name()].into_iter().flatten() {
                let arg = MethodArg::from_str(&name.to_uppercase(), true).unwrap();
                assert_eq!(Method::from(arg), m, "{name}");
                assert_eq!(name.to_uppercase().parse::<Method>().unwrap(), m, "{name}");
            }
        }
        assert!(MethodArg::from_str("circ", true).is_err());
        assert!("circ".parse::<Method>().is_err());
    }

    #[test]
    fn counts_are_refused_at_zero_and_over_the_limit() {
        assert_eq!(at_least_one("3"), Ok(3));
        assert_eq!(at_least_one("0"), Err("must be at least 1".into()));
        assert_eq!(
            run_count(&(MAX_RUNS + 1).to_string()),
            Err(format!("must be at most {MAX_RUNS}"))
        );
        assert_eq!(
            scenario_count(&MAX_SCENARIOS.to_string()),
            Ok(MAX_SCENARIOS)
        );
    }
}
