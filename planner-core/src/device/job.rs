//! The job: the request in progress or last finished, planned one form per poll, and the
//! finished result served in chunks.

use super::upload::Upload;
use super::Core;
use crate::chance::{ChanceSearch, ChanceStep};
use crate::error::PlanError;
use crate::model::form::Form;
use crate::model::scenario::Scenario;
use crate::wire::{
    ChanceRequest, DevicePlan, Fault, PlanRequest, PlanResult, ReplyBody, RequestError,
};

/// What a job plans with: every form once, or rounds of every form under a collision bound. One
/// search serves both (a plan without a bound is its session alone), filled in place: the
/// obstacles are decoded straight into its scenario and held there once.
pub(super) struct Planner {
    search: ChanceSearch,
    bounded: bool,
}

impl Planner {
    /// A planner with nothing to plan, all zero bytes.
    pub(super) const fn idle() -> Planner {
        Planner {
            search: ChanceSearch::idle(),
            bounded: false,
        }
    }

    /// The scenario last decoded into the planner.
    pub(super) fn scenario(&self) -> &Scenario {
        self.search.scenario()
    }

    /// The scenario to fill in place before [`Planner::start`].
    pub(super) fn scenario_mut(&mut self) -> &mut Scenario {
        self.search.scenario_mut()
    }

    /// Starts planning the scenario now held, under the collision bound `chance` if any.
    fn start(&mut self, chance: Option<ChanceRequest>) -> Result<(), PlanError> {
        self.bounded = chance.is_some();
        match chance {
            None => self.search.session_mut().restart(),
            Some(c) => self.search.start(c.model, c.bound, c.execution),
        }
    }

    fn forms_per_round(&mut self) -> usize {
        if self.bounded {
            self.search.forms_per_round()
        } else {
            self.search.session_mut().form_count()
        }
    }

    /// Plans one unit: `Ok(Some((round, form, feasible)))` for a form planned, `Ok(Some((round,
    /// None, _)))` for a round judged, `Ok(None)` once nothing is left.
    fn step(&mut self) -> Result<Option<(u32, Option<Form>, bool)>, PlanError> {
        if !self.bounded {
            let session = self.search.session_mut();
            return Ok(session.step().map(|o| (1, Some(o.form), o.feasible)));
        }
        Ok(self.search.step()?.map(|step| match step {
            ChanceStep::Form {
                round,
                form,
                feasible,
            } => (round, Some(form), feasible),
            ChanceStep::RoundEnded { round } => (round, None, false),
        }))
    }

    /// The finished plan as the device reports it.
    fn result(&mut self) -> PlanResult {
        if !self.bounded {
            return Ok(DevicePlan {
                planned: self.search.session_mut().take_scheduled(),
                chance: None,
            });
        }
        let planned = self.search.take_plan()?;
        let obstacles = self.search.scenario().obstacles.len();
        Ok(DevicePlan {
            chance: Some(planned.figures(obstacles)),
            planned: planned.planned,
        })
    }
}

/// What a device answers to a plan request for `scenario` (under the collision bound `chance`,
/// if any), computed here: the host's side of every bit-for-bit comparison.
///
/// ```
/// use planner_core::device::plan_as_device;
/// use planner_core::Scenario;
///
/// let answer = plan_as_device(&Scenario::paper(), None).unwrap();
/// assert!(answer.chance.is_none());
/// let here = planner_core::plan_scheduled(&Scenario::paper()).unwrap();
/// assert_eq!(format!("{:?}", answer.planned), format!("{here:?}"));
/// ```
pub fn plan_as_device(scenario: &Scenario, chance: Option<ChanceRequest>) -> PlanResult {
    // What the request's decoding refuses on the device (the host's scenario may hold more).
    let given = scenario.obstacles.len();
    if given > crate::DEVICE_MAX_OBSTACLES {
        return Err(PlanError::TooManyObstacles {
            given: given as u16,
            capacity: crate::DEVICE_MAX_OBSTACLES as u16,
        });
    }
    let mut planner = Planner::idle();
    planner.scenario_mut().clone_from(scenario);
    planner.start(chance)?;
    while planner.step()?.is_some() {}
    planner.result()
}

/// The request in progress or last finished (its planner is [`Core::plan`]).
pub(super) enum Job {
    Idle,
    Uploading {
        id: u16,
        total: u16,
        crc: u32,
        received: u16,
    },
    Planning {
        id: u16,
        total_bytes: u16,
        request_crc: u32,
        round: u8,
        done: u8,
        forms: u8,
        last: Option<(Form, bool)>,
    },
    Finished {
        id: u16,
        total_bytes: u16,
        request_crc: u32,
        len: u16,
        crc: u32,
    },
}

impl Core {
    /// Starts planning the uploaded request `id` (or stores the scenario's error as its result).
    /// The request is decoded into the planner's scenario in place.
    pub(super) fn start_plan(&mut self, id: u16, up: Upload, tx: &mut dyn FnMut(&[u8])) {
        let total = usize::from(up.total);
        let bytes = self.upload.get(..total).unwrap_or(&[]);
        let chance = match PlanRequest::decode_into(bytes, self.plan.scenario_mut()) {
            Ok(chance) => chance,
            Err(RequestError::Malformed) => {
                self.job = Job::Idle;
                self.stats.undecodable += 1;
                return self.fault(id, Fault::BadScenario, tx);
            }
            Err(RequestError::Refused(e)) => return self.store_result(id, up, &Err(e), tx),
        };
        match self.plan.start(chance) {
            Ok(()) => {
                let forms = self.plan.forms_per_round() as u8;
                self.job = Job::Planning {
                    id,
                    total_bytes: up.total,
                    request_crc: up.crc,
                    round: 1,
                    done: 0,
                    forms,
                    last: None,
                };
                self.status(id, tx);
            }
            Err(e) => self.store_result(id, up, &Err(e), tx),
        }
    }

    /// Plans one form of the active plan; false if there is none. Never inlined, like
    /// `handle_frame`: the solver's frames and a frame's decoded request then never share the
    /// stack.
    #[inline(never)]
    pub(super) fn step(&mut self, tx: &mut dyn FnMut(&[u8])) -> bool {
        let Job::Planning {
            id,
            total_bytes,
            request_crc,
            round,
            done,
            last,
            ..
        } = &mut self.job
        else {
            return false;
        };
        let id = *id;
        let up = Upload {
            offset: 0,
            total: *total_bytes,
            crc: *request_crc,
        };
        match self.plan.step() {
            Ok(Some((r, Some(form), feasible))) => {
                let r = u8::try_from(r).unwrap_or(u8::MAX);
                if r != *round {
                    *round = r;
                    *done = 0;
                }
                *last = Some((form, feasible));
                *done = done.saturating_add(1);
                self.status(id, tx);
            }
            // A round judged: its forms were reported one by one, the next round's follow.
            Ok(Some((_, None, _))) => {}
            Ok(None) => self.finish(id, up, tx),
            Err(e) => self.store_result(id, up, &Err(e), tx),
        }
        true
    }

    /// Picks the best form, builds its schedule and stores the encoded result. Never inlined, so
    /// its locals (the result) are not on the stack while [`Core::step`] plans a form.
    #[inline(never)]
    fn finish(&mut self, id: u16, up: Upload, tx: &mut dyn FnMut(&[u8])) {
        // Called once `step` found no work left.
        let result = self.plan.result();
        self.stats.plans += 1;
        self.store_result(id, up, &result, tx);
    }

    fn store_result(
        &mut self,
        id: u16,
        up: Upload,
        result: &PlanResult,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        match postcard::to_slice(result, &mut self.result) {
            Ok(bytes) => {
                let len = bytes.len() as u16;
                let crc = crate::wire::crc::crc32(bytes);
                self.job = Job::Finished {
                    id,
                    total_bytes: up.total,
                    request_crc: up.crc,
                    len,
                    crc,
                };
                self.send(id, ReplyBody::Finished { len, crc }, tx);
            }
            // Cannot happen: the buffer is sized from `PlanResult::MAX_SIZE`, checked by tests.
            Err(_) => {
                self.job = Job::Idle;
                self.fault(id, Fault::Undecodable, tx);
            }
        }
    }

    pub(super) fn status(&mut self, id: u16, tx: &mut dyn FnMut(&[u8])) {
        let body = match &self.job {
            Job::Uploading {
                id: a,
                total,
                received,
                ..
            } if *a == id => ReplyBody::Uploaded {
                received: *received,
                total: *total,
            },
            Job::Planning {
                id: a,
                round,
                done,
                forms,
                last,
                ..
            } if *a == id => ReplyBody::Progress {
                round: *round,
                done: *done,
                total: *forms,
                form: last.map(|(f, _)| f),
                feasible: last.is_some_and(|(_, ok)| ok),
            },
            Job::Finished {
                id: a, len, crc, ..
            } if *a == id => ReplyBody::Finished {
                len: *len,
                crc: *crc,
            },
            _ => ReplyBody::Fault(Fault::UnknownRequest),
        };
        self.send(id, body, tx);
    }

    pub(super) fn fetch(&mut self, id: u16, offset: u16, max_len: u16, tx: &mut dyn FnMut(&[u8])) {
        let len = match self.job {
            Job::Finished { id: a, len, .. } if a == id => len,
            _ => return self.status(id, tx),
        };
        let whole = self.result.get(..usize::from(len)).unwrap_or(&[]);
        let part = super::part_of(whole, offset, max_len);
        self.send(id, part, tx);
    }
}
