//! Steering on the device: the finished plan's schedule handed to the closed-loop controller,
//! one reading per request. Readings are answered at once (each is one bounded replan), so the
//! service stays responsive between them.

use super::job::Job;
use super::Core;
use crate::steer::{Pose, Reading, SteerConfig, SteerError, Steering, TipMeasurement};
use crate::wire::crc::crc32;
use crate::wire::{Fault, PlanRequest, PlanResult, ReplyBody};

/// The insertion being steered, if any.
// An enum with an explicit tag rather than an `Option`: the option's `None` hid in a niche of the
// controller as a byte 2, and that one byte put the whole service (30 KiB) in `.data`, copied from
// flash at boot, instead of `.bss` (see `DeviceService::new`).
// No heap to box the controller in (like `Job`).
#[allow(clippy::large_enum_variant)]
#[repr(u8)]
pub(super) enum Steered {
    /// Nothing is steered.
    Off,
    /// Plan `plan` is steered by `steering`.
    On { plan: u16, steering: Steering },
}

impl Core {
    /// Starts steering plan `id` with `config`. Never inlined: the controller it builds (a copy
    /// of the scenario among its state) is then not on the stack under every frame handled.
    #[inline(never)]
    pub(super) fn steer_start(
        &mut self,
        id: u16,
        config: &SteerConfig,
        max_len: u16,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        match self.steering_for(id, config) {
            Ok(steering) => {
                let steps = steering.steps().iter().copied().collect();
                self.steering = Steered::On { plan: id, steering };
                self.stop_driving();
                self.answer(id, ReplyBody::SteerStarted { steps }, None, max_len, tx);
            }
            Err(fault) => self.fault(id, fault, tx),
        }
    }

    /// The controller for plan `id`, from the stored request (decoded into the planner's
    /// scenario: the planner has finished) and result. Never inlined: the decoded result lives
    /// on this frame only.
    #[inline(never)]
    fn steering_for(&mut self, id: u16, config: &SteerConfig) -> Result<Steering, Fault> {
        let Job::Finished {
            id: plan,
            total_bytes,
            len,
            ..
        } = self.job
        else {
            return Err(Fault::NoPlan);
        };
        if plan != id {
            return Err(Fault::NoPlan);
        }
        let request = self
            .upload
            .get(..usize::from(total_bytes))
            .ok_or(Fault::NoPlan)?;
        let result = self.result.get(..usize::from(len)).ok_or(Fault::NoPlan)?;
        PlanRequest::decode_into(request, self.plan.scenario_mut()).map_err(|_| Fault::NoPlan)?;
        let scenario = self.plan.scenario();
        let planned = postcard::from_bytes::<PlanResult>(result)
            .ok()
            .and_then(|r| r.ok())
            .ok_or(Fault::NoPlan)?;
        let schedule = planned
            .planned
            .schedule
            .and_then(|s| s.ok())
            .ok_or(Fault::NoPlan)?;
        Steering::start(scenario, &schedule, config).map_err(|e| match e {
            SteerError::BadConfig => Fault::BadSteerConfig,
            _ => Fault::NoPlan,
        })
    }

    /// Answers one reading of the insertion steered under plan `id` (on a board that drives it,
    /// after its piece has ended, and then moves the next).
    pub(super) fn steer_reading(
        &mut self,
        id: u16,
        m: &TipMeasurement,
        max_len: u16,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        let mut m = *m;
        if let Err(fault) = self.drive_reading(id, &mut m) {
            return self.fault(id, fault, tx);
        }
        let reply = match &mut self.steering {
            Steered::On { plan, steering } if *plan == id => steering.update(&m),
            _ => return self.fault(id, Fault::NotSteering, tx),
        };
        self.stats.steer_readings = self.stats.steer_readings.wrapping_add(1);
        if let Err(fault) = self.drive_answer(id, m.seq, &reply) {
            return self.fault(id, fault, tx);
        }
        let stored = usize::from(self.steer_answer_len);
        if reply.reading == Reading::Repeated && stored > usize::from(max_len) {
            // The host may be fetching the first answer's parts: announce the same bytes again
            // rather than a re-encoding that says "repeated".
            let crc = crc32(&self.steer_answer[..stored]);
            let len = self.steer_answer_len;
            let reading = Some(m.seq);
            let pending = ReplyBody::SteerPending { reading, len, crc };
            return self.send(id, pending, tx);
        }
        let seq = Some(reply.seq);
        self.answer(id, ReplyBody::Steer(reply), seq, max_len, tx);
    }

    /// The counters, stop and estimated tip of the insertion steered under plan `id`.
    pub(super) fn steer_status(&mut self, id: u16, tx: &mut dyn FnMut(&[u8])) {
        match &self.steering {
            Steered::On { plan, steering } if *plan == id => {
                let body = ReplyBody::SteerStatus {
                    stats: steering.stats(),
                    stopped: steering.stopped(),
                    estimate: Pose::of_frame(&steering.estimate().tip),
                };
                self.send(id, body, tx);
            }
            _ => self.fault(id, Fault::NotSteering, tx),
        }
    }

    /// Sends a steering answer whole when it is at most `max_len` bytes, else announces it for
    /// `SteerFetch` (a noisy line damages long frames; short parts get through).
    fn answer(
        &mut self,
        id: u16,
        body: ReplyBody,
        reading: Option<u32>,
        max_len: u16,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        // Cannot fail: the buffer is sized from the largest steering answer, checked by tests.
        let Ok(bytes) = postcard::to_slice(&body, &mut self.steer_answer) else {
            return self.send(id, body, tx);
        };
        let len = bytes.len() as u16;
        let crc = crc32(bytes);
        self.steer_answer_len = len;
        if len <= max_len {
            self.send(id, body, tx);
        } else {
            self.send(id, ReplyBody::SteerPending { reading, len, crc }, tx);
        }
    }

    /// Part of the last steering answer of the insertion steered under plan `id`.
    pub(super) fn steer_fetch(
        &mut self,
        id: u16,
        offset: u16,
        max_len: u16,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        if !matches!(&self.steering, Steered::On { plan, .. } if *plan == id) {
            return self.fault(id, Fault::NotSteering, tx);
        }
        let len = usize::from(self.steer_answer_len);
        let whole = self.steer_answer.get(..len).unwrap_or(&[]);
        let part = super::part_of(whole, offset, max_len);
        self.send(id, part, tx);
    }
}
