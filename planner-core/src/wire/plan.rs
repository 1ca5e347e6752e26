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
    DEVICE_MAX_OBSTACLES,
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

    /// Decodes an encoded request (the whole of `bytes`) into `scenario`, writing each obstacle
    /// in its place: what [`postcard::from_bytes`] and [`PlanRequest::into_parts`] give, without
    /// the request and the scenario passing through the stack (16 bytes a sphere each). The
    /// encoding is the same. On an error `scenario` holds part of the request.
    pub fn decode_into(
        bytes: &[u8],
        scenario: &mut Scenario,
    ) -> Result<Option<ChanceRequest>, RequestError> {
        use postcard::take_from_bytes as take;
        let malformed = |_| RequestError::Malformed;
        let ((needle, entry, target), rest) =
            take::<(Needle, Entry, Target)>(bytes).map_err(malformed)?;
        // A sequence is its length, then its elements (as `WireObstacles` reads it).
        let (count, mut rest) = take::<u32>(rest).map_err(malformed)?;
        scenario.obstacles.clear();
        let mut given: u16 = 0;
        for _ in 0..count {
            let (o, more) = take::<Obstacle>(rest).map_err(malformed)?;
            rest = more;
            // Past capacity the element is still decoded (the request must be well-formed).
            let _ = scenario.obstacles.push(o);
            given = given.saturating_add(1);
        }
        type Tail = (Weights, PlannerOptions, Driver, Option<ChanceRequest>);
        let ((weights, options, driver, chance), rest) = take::<Tail>(rest).map_err(malformed)?;
        if !rest.is_empty() {
            return Err(RequestError::Malformed);
        }
        if usize::from(given) > DEVICE_MAX_OBSTACLES {
            return Err(RequestError::Refused(PlanError::TooManyObstacles {
                given,
                capacity: DEVICE_MAX_OBSTACLES as u16,
            }));
        }
        scenario.needle = needle;
        scenario.entry = entry;
        scenario.target = target;
        scenario.weights = weights;
        scenario.options = options;
        scenario.driver = driver;
        Ok(chance)
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

/// Why [`PlanRequest::decode_into`] gave no scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RequestError {
    /// The bytes are not an encoded plan request.
    Malformed,
    /// The request decoded, but the planner refuses it (more obstacles than the device holds).
    Refused(PlanError),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::perturbation::Perturbation;

    /// `n` spheres along the y axis, out of the paper's way.
    fn with_spheres(n: usize) -> Scenario {
        let mut s = Scenario::paper();
        s.obstacles.clear();
        for i in 0..n {
            let _ = s.obstacles.push(Obstacle {
                center: [(i % 16) as f32 * 3.0, 200.0 + (i / 16) as f32 * 3.0, 0.0],
                radius: 1.0 + i as f32 * 1e-3,
            });
        }
        s
    }

    fn encode(request: &PlanRequest) -> std::vec::Vec<u8> {
        let mut buf = [0u8; super::super::MAX_PLAN_REQUEST];
        postcard::to_slice(request, &mut buf).unwrap().to_vec()
    }

    #[test]
    fn decoding_in_place_gives_what_decoding_by_value_gives() {
        let chance = ChanceRequest {
            bound: 0.01,
            model: Perturbation::default(),
            execution: Execution::OpenLoop,
        };
        // A scenario already in place is replaced whole, however many obstacles it held.
        let mut into = with_spheres(DEVICE_MAX_OBSTACLES);
        for (s, c) in [
            (Scenario::paper(), None),
            (with_spheres(DEVICE_MAX_OBSTACLES), Some(chance)),
            (with_spheres(3), None),
        ] {
            let request = match c {
                None => PlanRequest::new(&s),
                Some(c) => PlanRequest::bounded(&s, c),
            };
            let bytes = encode(&request);
            let by_value = postcard::from_bytes::<PlanRequest>(&bytes).unwrap();
            let (scenario, chance) = by_value.into_parts().unwrap();
            assert_eq!(PlanRequest::decode_into(&bytes, &mut into), Ok(chance));
            assert_eq!(into, scenario);
            assert_eq!(into, s);
        }
    }

    #[test]
    fn decoding_in_place_refuses_what_decoding_by_value_refuses() {
        let mut into = Scenario::paper();
        let over = DEVICE_MAX_OBSTACLES + 1;
        let bytes = encode(&PlanRequest::new(&with_spheres(over)));
        let refused = PlanError::TooManyObstacles {
            given: over as u16,
            capacity: DEVICE_MAX_OBSTACLES as u16,
        };
        assert_eq!(
            PlanRequest::decode_into(&bytes, &mut into),
            Err(RequestError::Refused(refused))
        );
        let by_value = postcard::from_bytes::<PlanRequest>(&bytes).unwrap();
        assert_eq!(by_value.into_scenario(), Err(refused));
        // Cut short, or followed by a byte more: not a request either way.
        let bytes = encode(&PlanRequest::new(&with_spheres(5)));
        let longer = [bytes.as_slice(), &[0]].concat();
        for bad in [&bytes[..bytes.len() - 1], longer.as_slice()] {
            assert_eq!(
                PlanRequest::decode_into(bad, &mut into),
                Err(RequestError::Malformed)
            );
            let by_value = postcard::take_from_bytes::<PlanRequest>(bad);
            assert!(!matches!(by_value, Ok((_, []))));
        }
    }
}
