//! Steering on the device: start it on the plan just fetched, then one reading per exchange.
//! A reading is retried like any request; the device answers a repeated sequence number with
//! the same reply without applying the reading twice, so a retry after a lost answer is safe.
//! An answer longer than the current chunk (the schedule, a replaced continuation) is announced
//! and fetched in parts, so a noisy line that damages long frames still carries it.

use crate::client::Client;
use crate::error::LinkError;
use crate::transport::Transport;
use planner_core::execute::schedule::Steps;
use planner_core::steer::{Pose, SteerConfig, SteerReply, SteerStats, StopReason, TipMeasurement};
use planner_core::wire::{Fault, MotionStatus, ReplyBody, RequestBody};

/// A steering answer: here, or announced for fetching.
enum Answer<R> {
    Now(R),
    Pending { len: u16, crc: u32 },
}

impl<T: Transport> Client<T> {
    /// The request id of the plan last fetched, which steering runs under.
    fn steered_plan(&self) -> Result<u16, LinkError> {
        self.last_plan.ok_or(LinkError::Device(Fault::NoPlan))
    }

    /// Sends `make(chunk)` until the device answers with what `pick` takes, whole or announced
    /// (for `reading`: a sequence number, or `None` for the start) and then fetched in parts.
    fn steer_exchange<R>(
        &mut self,
        what: &'static str,
        (id, reading): (u16, Option<u32>),
        make: impl FnMut(usize) -> RequestBody,
        pick: impl Fn(&ReplyBody) -> Option<R>,
    ) -> Result<R, LinkError> {
        let answer = self.exchange_with(what, None, id, make, &mut |b| match b {
            // A late copy of an earlier announcement (the start's, a resent reading's) is
            // another answer's: only this one's is taken.
            ReplyBody::SteerPending {
                reading: r,
                len,
                crc,
            } if *r == reading => Some(Answer::Pending {
                len: *len,
                crc: *crc,
            }),
            other => pick(other).map(Answer::Now),
        })?;
        match answer {
            Answer::Now(r) => Ok(r),
            Answer::Pending { len, crc } => {
                let bytes = self.fetch_parts(what, id, len, crc, |offset, max_len| {
                    RequestBody::SteerFetch { offset, max_len }
                })?;
                postcard::from_bytes::<ReplyBody>(&bytes)
                    .ok()
                    .as_ref()
                    .and_then(pick)
                    .ok_or(LinkError::CorruptResult)
            }
        }
    }

    /// Starts steering the plan last fetched; returns the steps to execute first.
    pub fn steer_start(&mut self, config: &SteerConfig) -> Result<Steps, LinkError> {
        self.begin();
        let id = self.steered_plan()?;
        let config = *config;
        let make = |chunk: usize| RequestBody::SteerStart {
            config,
            max_len: chunk as u16,
        };
        self.steer_exchange("steer start", (id, None), make, |b| match b {
            ReplyBody::SteerStarted { steps } => Some(steps.clone()),
            _ => None,
        })
    }

    /// Sends one reading and returns the device's answer to it.
    pub fn steer(&mut self, m: &TipMeasurement) -> Result<SteerReply, LinkError> {
        self.begin();
        let id = self.steered_plan()?;
        let (reading, seq) = (*m, m.seq);
        let make = |chunk: usize| RequestBody::SteerReading {
            reading,
            max_len: chunk as u16,
        };
        self.steer_exchange("steer reading", (id, Some(seq)), make, |b| match b {
            ReplyBody::Steer(r) if r.seq == seq => Some(r.clone()),
            _ => None,
        })
    }

    /// Has the board move the steered insertion itself, at most `piece_mm` of insertion between
    /// readings: its motion status with the first piece queued. Each reading is then sent with
    /// [`Client::steer`] once the piece has ended (the motion status: armed, no moves left); the
    /// board fills in its own depth and base roll and moves the next piece. A repeat after a lost
    /// answer is answered with the status, the piece not queued twice.
    pub fn steer_drive(&mut self, piece_mm: f32) -> Result<MotionStatus, LinkError> {
        self.begin();
        let id = self.steered_plan()?;
        let body = RequestBody::SteerDrive { piece_mm };
        self.exchange("steer drive", id, &body, |b| match b {
            ReplyBody::Motion(s) => Some(*s),
            _ => None,
        })
    }

    /// The device controller's counters, and its stop once it has stopped.
    pub fn steer_status(&mut self) -> Result<(SteerStats, Option<StopReason>), LinkError> {
        self.steer_state()
            .map(|(stats, stopped, _)| (stats, stopped))
    }

    /// Where the device controller estimates the tip after the last reading (a viewer's
    /// drawing; the steering has it on the host).
    pub fn steer_estimate(&mut self) -> Result<Pose, LinkError> {
        self.steer_state().map(|(_, _, estimate)| estimate)
    }

    fn steer_state(&mut self) -> Result<(SteerStats, Option<StopReason>, Pose), LinkError> {
        self.begin();
        let id = self.steered_plan()?;
        self.exchange("steer status", id, &RequestBody::SteerStatus, |b| match b {
            ReplyBody::SteerStatus {
                stats,
                stopped,
                estimate,
            } => Some((*stats, *stopped, *estimate)),
            _ => None,
        })
    }
}
