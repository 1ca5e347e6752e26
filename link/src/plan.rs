//! A whole plan on the device: upload the request, wait while it plans, fetch the result.

use crate::client::{Client, Event};
use crate::error::{too_large, LinkError};
use crate::exchange::is_line_fault;
use crate::transport::Transport;
use planner_core::model::form::Form;
use planner_core::wire::{
    ChanceRequest, PlanRequest, PlanResult, ReplyBody, RequestBody, MAX_PLAN_REQUEST,
};
use planner_core::Scenario;
use std::time::{Duration, Instant};

/// One progress report of the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// The round of a plan under a collision bound (from 1; always 1 without one).
    pub round: u8,
    /// Forms done in this round.
    pub done: u8,
    /// Forms in all.
    pub total: u8,
    /// The form just finished.
    pub form: Option<Form>,
    /// Whether it gave a feasible path.
    pub feasible: bool,
}

impl<T: Transport> Client<T> {
    /// Plans `scenario` on the device: upload, wait (reporting progress), fetch.
    pub fn plan(
        &mut self,
        scenario: &Scenario,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<PlanResult, LinkError> {
        self.plan_bounded(scenario, None, progress)
    }

    /// Plans `scenario` on the device under the collision bound `chance` (none: as
    /// [`Client::plan`]).
    pub fn plan_bounded(
        &mut self,
        scenario: &Scenario,
        chance: Option<ChanceRequest>,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<PlanResult, LinkError> {
        let given = scenario.obstacles.len();
        if given > planner_core::wire::WIRE_MAX_OBSTACLES {
            // More than a request can carry: the answer the device gives any request over its
            // capacity, without sending what it could not receive.
            return Ok(Err(planner_core::PlanError::TooManyObstacles {
                given: given.min(usize::from(u16::MAX)) as u16,
                capacity: planner_core::DEVICE_MAX_OBSTACLES as u16,
            }));
        }
        let mut buf = vec![0u8; MAX_PLAN_REQUEST];
        let request = PlanRequest {
            chance,
            ..PlanRequest::new(scenario)
        };
        let request = postcard::to_slice(&request, &mut buf)
            .map_err(|_| too_large("scenario too large to encode"))?
            .to_vec();
        self.plan_encoded(&request, progress)
    }

    /// Plans an already encoded [`PlanRequest`] (tests use it to send what a scenario cannot hold).
    pub fn plan_encoded(
        &mut self,
        request: &[u8],
        progress: &mut dyn FnMut(Progress),
    ) -> Result<PlanResult, LinkError> {
        self.begin();
        let id = self.new_id();
        self.finished = None;
        let result = self.upload(id, request).and_then(|()| {
            let (len, crc) = self.await_plan(id, progress)?;
            self.fetch(id, len, crc)
        });
        match result {
            Ok(bytes) => {
                let result = postcard::from_bytes::<PlanResult>(&bytes)
                    .map_err(|_| LinkError::CorruptResult)?;
                self.last_plan = Some(id);
                Ok(result)
            }
            Err(e) => {
                // Leave the device free for the next request: one cancel, without waiting (the
                // line may be dead), and remember the id in case it never arrived.
                self.abandoned = Some(id);
                let _ = self.send(id, &RequestBody::Cancel);
                Err(e)
            }
        }
    }

    /// Waits for request `id`'s `Finished { len, crc }`, passing on progress reports. After a
    /// silence of three times the longest gap between reports so far (at least the resend
    /// interval, at most `timeout`), or a damaged frame, it asks for the status, unless planning
    /// is quiet. Ends at the operation's deadline.
    fn await_plan(
        &mut self,
        id: u16,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(u16, u32), LinkError> {
        let mut news = Progress {
            round: 1,
            done: 0,
            total: 0,
            form: None,
            feasible: false,
        };
        let mut last_news = Instant::now();
        let mut longest_gap = Duration::ZERO;
        let mut seen = (1u8, 0u8);
        loop {
            if let Some((fid, len, crc)) = self.finished.take() {
                if fid == id {
                    return Ok((len, crc));
                }
            }
            let now = Instant::now();
            if let Some((end, limit)) = self.deadline() {
                if now >= end {
                    return Err(LinkError::PlanTooLong {
                        done: (news.done, news.total),
                        after: self.op_start.elapsed(),
                        limit,
                    });
                }
            }
            let silence = self.quiet_planning.unwrap_or_else(|| {
                (longest_gap * 3)
                    .max(self.resend_interval(0))
                    .min(self.config.timeout)
            });
            let deadline = self.deadline();
            let mut until = now + silence;
            if let Some((end, _)) = deadline {
                until = until.min(end);
            }
            let event = match self.next_event(until) {
                Err(LinkError::Io(e)) => return Err(self.lost("plan status", e)),
                other => other?,
            };
            let ask = match event {
                // The wait ran to `until` (in-process silence costs no time): the deadline, or
                // the silence allowed.
                None => {
                    self.stats.timeouts += 1;
                    if let Some((_, limit)) = deadline.filter(|d| until == d.0) {
                        return Err(LinkError::PlanTooLong {
                            done: (news.done, news.total),
                            after: self.op_start.elapsed(),
                            limit,
                        });
                    }
                    if self.quiet_planning.is_some() {
                        return Err(LinkError::NoResult { waited: silence });
                    }
                    true
                }
                Some(Event::Damaged) => {
                    // Perhaps the report that the plan is done: ask rather than wait. A quiet
                    // session runs on a clean line and keeps waiting instead.
                    self.stats.detected += 1;
                    self.quiet_planning.is_none()
                }
                Some(Event::Reply(r)) if r.header.id == id => {
                    self.on_plan_news(id, &r.body, &mut news, progress)?;
                    false
                }
                Some(Event::Reply(_)) => {
                    self.stats.stale += 1;
                    false
                }
            };
            if ask {
                let reply = self.exchange("plan status", id, &RequestBody::Status, |b| {
                    matches!(b, ReplyBody::Progress { .. } | ReplyBody::Finished { .. })
                        .then(|| b.clone())
                })?;
                self.on_plan_news(id, &reply, &mut news, progress)?;
            }
            if (news.round, news.done) != seen {
                let now = Instant::now();
                seen = (news.round, news.done);
                longest_gap = longest_gap.max(now - last_news);
                last_news = now;
            }
        }
    }

    /// Takes one report about request `id`; progress reports older than `news` (answers to
    /// repeated status requests) are dropped.
    fn on_plan_news(
        &mut self,
        id: u16,
        body: &ReplyBody,
        news: &mut Progress,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), LinkError> {
        match *body {
            ReplyBody::Progress {
                round,
                done,
                total,
                form,
                feasible,
            } if (round, done) > (news.round, news.done) || news.total == 0 => {
                *news = Progress {
                    round,
                    done,
                    total,
                    form,
                    feasible,
                };
                progress(*news);
            }
            ReplyBody::Finished { len, crc } => {
                self.finished = Some((id, len, crc));
            }
            ReplyBody::Fault(f) if !is_line_fault(f) => return Err(LinkError::Device(f)),
            _ => {}
        }
        Ok(())
    }
}
