//! The plan request as uploaded and the plan result as fetched: the two large messages, sent in
//! chunks (see [`RequestBody::Upload`](super::RequestBody::Upload) and
//! [`RequestBody::Fetch`](super::RequestBody::Fetch)).

use super::max_size::MaxSize;
use super::obstacles::{WireObstacles, WIRE_MAX_OBSTACLES};
use crate::chance::ChanceFigures;
use crate::error::PlanError;
use crate::execute::perturbation::Perturbation;
use crate::execute::plan_with_schedule::ScheduledPlan;
use crate::execute::risk::Execution;
use crate::model::scenario::{
    Driver, Entry, Needle, Obstacle, PlannerOptions, Scenario, Target, Weights,
};
use serde::{Deserialize, Serialize};

/// The planning problem as uploaded: the scenario with a counted obstacle list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanRequest {
    /// Needle mechanics.
    pub needle: Needle,
    /// Entry.
    pub entry: Entry,
    /// Target.
    pub target: Target,
    /// Obstacles.
    pub obstacles: WireObstacles,
    /// Weights.
    pub weights: Weights,
    /// Planner options.
    pub options: PlannerOptions,
    /// The driver that will execute the plan.
    pub driver: Driver,
    /// Plan under a bound on the predicted collision probability
    /// ([`ChanceSearch`](crate::chance::ChanceSearch)); `None` plans without one.
    pub chance: Option<ChanceRequest>,
}

/// What a plan under a collision bound needs beyond the scenario.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChanceRequest {
    /// The largest predicted probability of entering an obstacle, in (0, 1).
    pub bound: f32,
    /// The execution's perturbation model.
    pub model: Perturbation,
    /// How the plan will be executed (the spread differs open loop and steered).
    pub execution: Execution,
}

impl PlanRequest {
    /// The request for a scenario.
    pub fn new(s: &Scenario) -> Self {
        PlanRequest {
            needle: s.needle,
            entry: s.entry,
            target: s.target,
            obstacles: WireObstacles::from_obstacles(&s.obstacles),
            weights: s.weights,
            options: s.options,
            driver: s.driver,
            chance: None,
        }
    }

    /// The request for a scenario planned under a collision bound.
    pub fn bounded(s: &Scenario, chance: ChanceRequest) -> Self {
        PlanRequest {
            chance: Some(chance),
            ..PlanRequest::new(s)
        }
    }

    /// The scenario (and the bound, if any), or the typed error for more obstacles than the
    /// planner holds.
    pub fn into_parts(self) -> Result<(Scenario, Option<ChanceRequest>), PlanError> {
        let chance = self.chance;
        Ok((self.into_scenario()?, chance))
    }

    /// The scenario, or the typed error for more obstacles than the planner holds.
    pub fn into_scenario(self) -> Result<Scenario, PlanError> {
        Ok(Scenario {
            needle: self.needle,
            entry: self.entry,
            target: self.target,
            obstacles: self.obstacles.into_obstacles()?,
            weights: self.weights,
            options: self.options,
            driver: self.driver,
        })
    }
}

/// What a plan ends with: the report with its best form's motor schedule, or the planner's typed
/// error.
pub type PlanResult = Result<DevicePlan, PlanError>;

/// A finished plan as a device reports it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DevicePlan {
    /// The report with its best form's motor schedule (under a bound, that of the round the
    /// search settled on: its clearances are to the grown obstacles).
    pub planned: ScheduledPlan,
    /// Under a collision bound, what the plan achieved; `None` without one.
    pub chance: Option<ChanceFigures>,
}

impl MaxSize for PlanRequest {
    const MAX_SIZE: usize = Needle::MAX_SIZE
        + Entry::MAX_SIZE
        + Target::MAX_SIZE
        + heapless::Vec::<Obstacle, WIRE_MAX_OBSTACLES>::MAX_SIZE
        + Weights::MAX_SIZE
        + PlannerOptions::MAX_SIZE
        + Driver::MAX_SIZE
        + Option::<ChanceRequest>::MAX_SIZE;
}

impl MaxSize for ChanceRequest {
    const MAX_SIZE: usize = f32::MAX_SIZE + Perturbation::MAX_SIZE + Execution::MAX_SIZE;
}

impl MaxSize for DevicePlan {
    const MAX_SIZE: usize = ScheduledPlan::MAX_SIZE + Option::<ChanceFigures>::MAX_SIZE;
}
