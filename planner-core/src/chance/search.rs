//! The search for margins as a job that can be paused between forms: a device plans one form
//! per poll (answering pings and cancels in between), the host runs it to the end, and both get
//! the same plan bit for bit because it is the same code.

use super::margins::raise_margins;
use super::{ChancePlan, MAX_ROUNDS};
use crate::execute::perturbation::Perturbation;
use crate::execute::risk::{risk_by_obstacle, Execution, ObstacleRisk};
use crate::execute::schedule::schedule;
use crate::model::form::{Form, FORM_COUNT};
use crate::model::scenario::Scenario;
use crate::session::PlanSession;
use crate::{Field, PlanError, MAX_OBSTACLES};

/// What one [`ChanceSearch::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChanceStep {
    /// Planned `form` in round `round` (counted from 1).
    Form {
        /// The round (one plan of every form, obstacles grown by that round's margins).
        round: u32,
        /// The form planned.
        form: Form,
        /// Whether it gave a feasible path.
        feasible: bool,
    },
    /// Judged round `round`'s plan against the bound, and started the next round or ended.
    RoundEnded {
        /// The round judged.
        round: u32,
    },
}

/// A plan under a collision bound, made one unit of work at a time.
///
/// ```
/// use planner_core::chance::{plan_within_risk, ChanceSearch, ChanceStep};
/// use planner_core::execute::perturbation::Perturbation;
/// use planner_core::execute::risk::Execution;
/// use planner_core::Scenario;
///
/// let scenario = Scenario::paper();
/// let model = Perturbation::default();
/// let mut search = ChanceSearch::new(scenario.clone(), model, 0.01, Execution::OpenLoop).unwrap();
/// let mut rounds = 0;
/// while let Some(step) = search.step().unwrap() {
///     if let ChanceStep::RoundEnded { .. } = step {
///         rounds += 1;
///     }
/// }
/// let planned = search.finish().unwrap();
/// assert_eq!(planned.rounds, rounds);
/// // The same plan as the one-call form, bit for bit (NaN figures of infeasible forms included).
/// let whole = plan_within_risk(&scenario, &model, 0.01).unwrap();
/// assert_eq!(format!("{planned:?}"), format!("{whole:?}"));
/// ```
pub struct ChanceSearch {
    /// The round being planned. Its scenario is the one given, with each obstacle grown by this
    /// round's margins while a round is planned and at its true radius otherwise: the obstacles
    /// are held once, and a device fills them in place.
    session: PlanSession,
    /// Each obstacle's true radius, in the scenario's order.
    radii: [f32; MAX_OBSTACLES],
    limit: Limit,
    /// This round's margins.
    margins: [f32; MAX_OBSTACLES],
    /// The margins of the last round that found a path: a round whose grown obstacles leave none
    /// backs off half way towards them.
    found: [f32; MAX_OBSTACLES],
    round: u32,
    /// A round is being planned (false before the start and once the search has ended).
    planning: bool,
    /// The last round that found a path, and once the search has ended, its result.
    last: Held<ChancePlan>,
    /// Why the search could not go on (a grown scenario the planner refused).
    failed: Held<PlanError>,
}

/// An `Option` whose empty value is zero bytes: `None` of an `Option<ChancePlan>` lies in a niche
/// (a `bool` of 2), which would put a device's whole service in `.data`, copied from flash.
#[repr(u8)]
enum Held<T> {
    Empty,
    Full(T),
}

impl<T> Held<T> {
    fn get(&self) -> Option<&T> {
        match self {
            Held::Full(t) => Some(t),
            Held::Empty => None,
        }
    }

    fn get_mut(&mut self) -> Option<&mut T> {
        match self {
            Held::Full(t) => Some(t),
            Held::Empty => None,
        }
    }

    fn take(&mut self) -> Option<T> {
        match core::mem::replace(self, Held::Empty) {
            Held::Full(t) => Some(t),
            Held::Empty => None,
        }
    }
}

/// What a round's plan is judged by. An enum with its tag first and `Unset` zero, so that a
/// search in a static is all zero bytes (`.bss`, not an image in flash copied at boot).
#[derive(Clone, Copy)]
#[repr(u8)]
enum Limit {
    Unset,
    Set {
        model: Perturbation,
        bound: f32,
        execution: Execution,
    },
}

impl Limit {
    /// The model, bound and execution set, or `Unreachable` before they are.
    fn set(&self) -> Result<(Perturbation, f32, Execution), PlanError> {
        match *self {
            Limit::Set {
                model,
                bound,
                execution,
            } => Ok((model, bound, execution)),
            Limit::Unset => Err(PlanError::Unreachable),
        }
    }
}

impl ChanceSearch {
    /// Checks the bound (in (0, 1)) and the scenario, and prepares the first round: the
    /// scenario as it is.
    pub fn new(
        scenario: Scenario,
        model: Perturbation,
        bound: f32,
        execution: Execution,
    ) -> Result<Self, PlanError> {
        let mut search = ChanceSearch::idle();
        *search.session.scenario_mut() = scenario;
        search.start(model, bound, execution)?;
        Ok(search)
    }

    /// A search of nothing, all zero bytes: filled in place by [`ChanceSearch::scenario_mut`]
    /// and [`ChanceSearch::start`].
    pub(crate) const fn idle() -> ChanceSearch {
        ChanceSearch {
            session: PlanSession::idle(),
            radii: [0.0; MAX_OBSTACLES],
            limit: Limit::Unset,
            margins: [0.0; MAX_OBSTACLES],
            found: [0.0; MAX_OBSTACLES],
            round: 0,
            planning: false,
            last: Held::Empty,
            failed: Held::Empty,
        }
    }

    /// [`ChanceSearch::new`] in place, for the scenario now held: checks the bound and the
    /// scenario and prepares the first round, forgetting any earlier search.
    pub(crate) fn start(
        &mut self,
        model: Perturbation,
        bound: f32,
        execution: Execution,
    ) -> Result<(), PlanError> {
        self.planning = false;
        self.last = Held::Empty;
        self.failed = Held::Empty;
        self.round = 1;
        self.margins.fill(0.0);
        self.found.fill(0.0);
        if !bound.is_finite() {
            return Err(PlanError::NotFinite(Field::MaxCollisionProbability));
        }
        if !(bound > 0.0 && bound < 1.0) {
            return Err(PlanError::OutOfRange(Field::MaxCollisionProbability));
        }
        self.limit = Limit::Set {
            model,
            bound,
            execution,
        };
        for (r, ob) in self
            .radii
            .iter_mut()
            .zip(&self.session.scenario().obstacles)
        {
            *r = ob.radius;
        }
        self.session.restart()?;
        self.planning = true;
        Ok(())
    }

    /// The scenario: its obstacles are grown by the round's margins while a round is planned,
    /// and true once the search has ended.
    pub fn scenario(&self) -> &Scenario {
        self.session.scenario()
    }

    /// The scenario, to fill in place before [`ChanceSearch::start`].
    pub(crate) fn scenario_mut(&mut self) -> &mut Scenario {
        self.session.scenario_mut()
    }

    /// The session that plans each round (a device plans without a bound in it too).
    pub(crate) fn session_mut(&mut self) -> &mut PlanSession {
        &mut self.session
    }

    /// Forms planned in each round.
    pub fn forms_per_round(&self) -> usize {
        if self.planning {
            self.session.form_count()
        } else {
            0
        }
    }

    /// Plans one form, or judges a finished round; `Ok(None)` once the search has ended. `Err`
    /// when a round's grown scenario cannot be planned; the search is then over.
    pub fn step(&mut self) -> Result<Option<ChanceStep>, PlanError> {
        if let Some(e) = self.failed.get() {
            return Err(*e);
        }
        if !self.planning {
            return Ok(None);
        }
        let round = self.round;
        if let Some(o) = self.session.step() {
            let (form, feasible) = (o.form, o.feasible);
            return Ok(Some(ChanceStep::Form {
                round,
                form,
                feasible,
            }));
        }
        match self.end_round() {
            Ok(()) => Ok(Some(ChanceStep::RoundEnded { round })),
            Err(e) => {
                self.failed = Held::Full(e);
                Err(e)
            }
        }
    }

    /// Runs what is left and returns the plan the search settled on.
    pub fn finish(mut self) -> Result<ChancePlan, PlanError> {
        while self.step()?.is_some() {}
        self.take_plan()
    }

    /// The plan the search settled on, once [`ChanceSearch::step`] has returned `Ok(None)`
    /// (planning nothing itself, so that the solver's frames are not under the caller's).
    pub(crate) fn take_plan(&mut self) -> Result<ChancePlan, PlanError> {
        if let Some(e) = self.failed.get() {
            return Err(*e);
        }
        // Every ending sets `last`; a search still planning has none to give.
        match self.planning {
            true => Err(PlanError::Unreachable),
            false => self.last.take().ok_or(PlanError::Unreachable),
        }
    }

    /// Judges the finished round's plan: done when it keeps the bound (or no path exists even
    /// without margins); otherwise the margins grow (or back off after a round without a path)
    /// and the next round starts. Never inlined, so its locals are not on the stack while a
    /// form is planned.
    #[inline(never)]
    fn end_round(&mut self) -> Result<(), PlanError> {
        let (model, bound, execution) = self.limit.set()?;
        self.planning = false;
        // The schedule of the plan as made, around the grown obstacles; judged on the true ones.
        let planned = self.session.take_scheduled();
        self.set_radii(false);
        let mut by_obstacle = [ObstacleRisk::default(); MAX_OBSTACLES];
        let risk = match &planned.schedule {
            Some(Ok(s)) => Some(risk_by_obstacle(
                self.session.scenario(),
                s,
                &model,
                execution,
                &mut by_obstacle,
            )),
            _ => None,
        };
        let within_bound = risk.is_some_and(|r| r.collision_probability <= bound);
        let outcome = ChancePlan {
            planned,
            risk,
            margins: self.margins,
            rounds: self.round,
            within_bound,
        };
        if within_bound {
            self.last = Held::Full(outcome);
            return Ok(());
        }
        if risk.is_none() {
            let Some(last) = self.last.get_mut() else {
                self.last = Held::Full(outcome); // no path even without margins
                return Ok(());
            };
            last.rounds = self.round;
            if self.margins == self.found {
                return self.conclude();
            }
            for (m, f) in self.margins.iter_mut().zip(&self.found) {
                *m = 0.5 * (*m + f);
            }
            return self.next_round();
        }
        self.found = self.margins;
        self.last = Held::Full(outcome);
        let scenario = self.session.scenario();
        if !raise_margins(scenario, bound, &by_obstacle, &mut self.margins) {
            return self.conclude();
        }
        self.next_round()
    }

    /// Each obstacle at its true radius, or grown by this round's margin (the same sum a copy of
    /// the scenario grown from the true one would hold).
    fn set_radii(&mut self, grown: bool) {
        let obstacles = &mut self.session.scenario_mut().obstacles;
        for ((ob, r), m) in obstacles.iter_mut().zip(&self.radii).zip(&self.margins) {
            ob.radius = if grown { *r + *m } else { *r };
        }
    }

    fn next_round(&mut self) -> Result<(), PlanError> {
        if self.round >= MAX_ROUNDS {
            return self.conclude();
        }
        self.round += 1;
        self.set_radii(true);
        self.session.restart()?;
        self.planning = true;
        Ok(())
    }

    /// Ends the search on the last round that found a path.
    fn conclude(&mut self) -> Result<(), PlanError> {
        let (model, bound, execution) = self.limit.set()?;
        let last = self.last.get_mut().ok_or(PlanError::Unreachable)?;
        within_bound_by_another_form(self.session.scenario(), &model, bound, execution, last);
        Ok(())
    }
}

/// Where the best form misses the bound, the form of lowest objective among those of the same
/// plan that keep it becomes the best (a longer form may pass the spheres where the spread is
/// smaller), if any does.
fn within_bound_by_another_form(
    scenario: &Scenario,
    model: &Perturbation,
    bound: f32,
    execution: Execution,
    plan: &mut ChancePlan,
) {
    let report = &plan.planned.report;
    let mut order = [0u8; FORM_COUNT];
    let mut n = 0;
    for (i, o) in report.forms.iter().enumerate() {
        if o.feasible && Some(i as u8) != report.best && n < order.len() {
            order[n] = i as u8;
            n += 1;
        }
    }
    let forms = &report.forms;
    order[..n].sort_unstable_by(|&a, &b| {
        let f = |i: u8| {
            forms
                .get(usize::from(i))
                .map_or(f32::INFINITY, |o| o.objective)
        };
        f(a).total_cmp(&f(b))
    });
    let mut by_obstacle = [ObstacleRisk::default(); MAX_OBSTACLES];
    for &i in &order[..n] {
        let Some(outcome) = forms.get(usize::from(i)) else {
            continue;
        };
        let Ok(s) = schedule(scenario, outcome) else {
            continue;
        };
        let risk = risk_by_obstacle(scenario, &s, model, execution, &mut by_obstacle);
        if risk.collision_probability <= bound {
            plan.planned.report.best = Some(i);
            plan.planned.schedule = Some(Ok(s));
            plan.risk = Some(risk);
            plan.within_bound = true;
            return;
        }
    }
}
