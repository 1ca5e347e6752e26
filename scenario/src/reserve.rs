//! The curvature reserve a plan keeps when no path keeps all it was asked for: one rule for
//! every command that plans (`needle plan`, `send`, `simulate`, `steer`, the benchmark and the
//! Python package), so each plans the path the others steer.
//!
//! Where no path exists at the reserve asked for (a target close behind an obstacle needs the
//! needle's full bend), the reserve is halved while it stays at least
//! [`LEAST_CURVATURE_RESERVE`]; where paths exist but none keeps the collision bound, it is
//! lowered by [`RESERVE_STEP_FOR_BOUND`] while it stays at least
//! [`LEAST_CURVATURE_RESERVE_FOR_BOUND`] (a wider needle bend has more room around the spheres).
//! A scenario without a reserve is planned as it is.

use planner_core::Scenario;

/// The least curvature reserve a plan steered with a reserve keeps: with less, a tissue that
/// bends a few percent less than assumed leaves the target out of reach too often to steer for
/// (docs/execution.md, "Curvature in hand": such plans reached the target in 8 to 45 % of runs).
pub const LEAST_CURVATURE_RESERVE: f32 = 0.1;

/// The least curvature reserve given up to meet a collision bound: a plan that meets the bound
/// only with less is refused for it rather than steered with too little curvature in hand
/// (docs/execution.md, "The closed loop under its own bound": plans kept at 0.1 to meet it
/// missed the target in 2 % of runs).
pub const LEAST_CURVATURE_RESERVE_FOR_BOUND: f32 = 0.15;

/// How much curvature reserve one more try at the bound gives up.
pub const RESERVE_STEP_FOR_BOUND: f32 = 0.05;

/// Why a plan at some reserve was not taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shortfall {
    /// No form reaches the target at this share of the curvature.
    Unreachable,
    /// Forms reach it, but none keeps the collision bound.
    MissesBound,
}

/// The reserve to try after a plan at `reserve` fell short for `why`; `None` when the rule
/// gives up (no reserve to give, or the next would be under its floor).
///
/// ```
/// use needle_scenario::reserve::{next_reserve, Shortfall};
///
/// assert_eq!(next_reserve(0.4, Shortfall::Unreachable), Some(0.2));
/// assert_eq!(next_reserve(0.15, Shortfall::Unreachable), None);
/// assert!((next_reserve(0.4, Shortfall::MissesBound).unwrap() - 0.35).abs() < 1e-6);
/// assert_eq!(next_reserve(0.15, Shortfall::MissesBound), None);
/// assert_eq!(next_reserve(0.0, Shortfall::MissesBound), None);
/// ```
pub fn next_reserve(reserve: f32, why: Shortfall) -> Option<f32> {
    if reserve.is_nan() || reserve <= 0.0 {
        return None;
    }
    let next = match why {
        Shortfall::Unreachable => 0.5 * reserve,
        Shortfall::MissesBound => reserve - RESERVE_STEP_FOR_BOUND,
    };
    let floor = match why {
        Shortfall::Unreachable => LEAST_CURVATURE_RESERVE,
        // The steps of 0.05 land a rounding away from the floor.
        Shortfall::MissesBound => LEAST_CURVATURE_RESERVE_FOR_BOUND - 1e-4,
    };
    (next >= floor).then_some(next)
}

/// Plans `scenario` with `attempt`, lowering its curvature reserve by [`next_reserve`] while
/// `short` says the attempt fell short. Returns the scenario of the last attempt (the reserve it
/// planned with) and what that attempt gave, kept or not: the caller reports it as it is.
pub fn keeping_reserve<T, E>(
    scenario: &Scenario,
    mut attempt: impl FnMut(&Scenario) -> Result<T, E>,
    short: impl Fn(&Result<T, E>) -> Option<Shortfall>,
) -> (Scenario, Result<T, E>) {
    let mut s = scenario.clone();
    loop {
        let made = attempt(&s);
        let next = short(&made).and_then(|why| next_reserve(s.options.curvature_reserve, why));
        match next {
            Some(reserve) => s.options.curvature_reserve = reserve,
            None => return (s, made),
        }
    }
}

/// Whether `e` says no form reaches the target.
pub fn is_unreachable(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<planner_core::PlanError>(),
            Some(planner_core::PlanError::Unreachable)
        )
    })
}

/// The line a table prints when a path kept less of the reserve than asked (none when it kept
/// it all): a lab that asked for more reach must see it did not get it.
pub fn reserve_line(planned: f32, asked: f32) -> String {
    if planned >= asked {
        return String::new();
    }
    let share = |v: f32| {
        let text = format!("{v:.3}");
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    };
    format!(
        "curvature reserve: {} planned, {} asked (no path keeping more reached the target \
         within the collision bound)\n",
        share(planned),
        share(asked)
    )
}
