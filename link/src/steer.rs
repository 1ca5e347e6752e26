//! Steering on the device: start it on the plan just fetched, then one reading per exchange.
//! A reading is retried like any request; the device answers a repeated sequence number with
//! the same reply without applying the reading twice, so a retry after a lost answer is safe.

use crate::client::Client;
use crate::error::LinkError;
use crate::transport::Transport;
use planner_core::execute::schedule::Steps;
use planner_core::steer::{SteerConfig, SteerReply, SteerStats, StopReason, TipMeasurement};
use planner_core::wire::{Fault, ReplyBody, RequestBody};

impl<T: Transport> Client<T> {
    /// The request id of the plan last fetched, which steering runs under.
    fn steered_plan(&self) -> Result<u16, LinkError> {
        self.last_plan.ok_or(LinkError::Device(Fault::NoPlan))
    }

    /// Starts steering the plan last fetched; returns the steps to execute first.
    pub fn steer_start(&mut self, config: &SteerConfig) -> Result<Steps, LinkError> {
        self.begin();
        let id = self.steered_plan()?;
        let body = RequestBody::SteerStart { config: *config };
        self.exchange("steer start", id, &body, |b| match b {
            ReplyBody::SteerStarted { steps } => Some(steps.clone()),
            _ => None,
        })
    }

    /// Sends one reading and returns the device's answer to it.
    pub fn steer(&mut self, m: &TipMeasurement) -> Result<SteerReply, LinkError> {
        self.begin();
        let id = self.steered_plan()?;
        let seq = m.seq;
        self.exchange(
            "steer reading",
            id,
            &RequestBody::SteerReading(*m),
            |b| match b {
                ReplyBody::Steer(r) if r.seq == seq => Some(r.clone()),
                _ => None,
            },
        )
    }

    /// The device controller's counters, and its stop once it has stopped.
    pub fn steer_status(&mut self) -> Result<(SteerStats, Option<StopReason>), LinkError> {
        self.begin();
        let id = self.steered_plan()?;
        self.exchange("steer status", id, &RequestBody::SteerStatus, |b| match b {
            ReplyBody::SteerStatus { stats, stopped } => Some((*stats, *stopped)),
            _ => None,
        })
    }
}
