//! A closed loop whose driver board moves the needle itself: the board cuts the controller's
//! continuation into pieces ([`Pieces`]) and moves one at a time; after each piece has ended the
//! world takes it (the tissue bends the needle), the tracker reads the tip and the reading is
//! relayed to the board, whose controller answers and whose axes move the next piece.
//!
//! The loop keeps its own copy of the pieces (the same cut from the same steps and answers), so
//! it knows what the board moved without being told. With the in-process [`Steering`] as the
//! board (no axes), the run is what a board's should be, bit for bit: the host's simulation of
//! the board's insertion.

use crate::closed::{ClosedLoopError, ClosedRun, Conditions, Ended, Tracker};
use crate::run::Planned;
use crate::world::{World, WorldError};
use planner_core::execute::pieces::Pieces;
use planner_core::execute::schedule::Schedule;
use planner_core::steer::{
    Command, SteerError, SteerReply, SteerStats, Steering, StopReason, TipMeasurement,
};
use planner_core::Scenario;
use std::ops::ControlFlow;

/// A driver board that steers and moves: its controller started on the schedule, its axes at
/// the entry.
pub trait Board {
    /// Why the board could not be reached or refused.
    type Error;
    /// Starts moving the insertion in pieces of at most `piece_mm`: the first now.
    fn drive(&mut self, piece_mm: f32) -> Result<(), Self::Error>;
    /// Returns once the piece moving has ended.
    fn piece_ended(&mut self) -> Result<(), Self::Error>;
    /// Relays one reading; the controller's answer (the board moves on by it).
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, Self::Error>;
    /// The controller's counters.
    fn stats(&mut self) -> Result<SteerStats, Self::Error>;
}

/// The host's own simulation of a board: the in-process controller, no axes (a piece ends at
/// once).
impl Board for Steering {
    type Error = std::convert::Infallible;
    fn drive(&mut self, _piece_mm: f32) -> Result<(), Self::Error> {
        Ok(())
    }
    fn piece_ended(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, Self::Error> {
        Ok(Steering::update(self, m))
    }
    fn stats(&mut self) -> Result<SteerStats, Self::Error> {
        Ok(Steering::stats(self))
    }
}

/// Runs one insertion in the world of `seed`, moved by `board` in pieces of at most `piece_mm`
/// (its controller started on `schedule`). Each reading carries the pieces' commanded depth and
/// base roll, as the board's own count would.
pub fn driven_loop<B: Board>(
    scenario: &Scenario,
    planned: &Planned,
    schedule: &Schedule,
    conditions: &Conditions<'_>,
    board: &mut B,
    seed: u64,
    piece_mm: f32,
) -> Result<ClosedRun, ClosedLoopError<B::Error>> {
    let (p, effects) = (conditions.perturbation, conditions.effects);
    let mut world =
        World::with_effects(scenario, schedule, p, effects, seed).map_err(|e| match e {
            WorldError::Perturbation(e) => ClosedLoopError::Perturbation(e),
            WorldError::Effects(e) => ClosedLoopError::Effects(e),
        })?;
    let mut pieces = Pieces::new(&schedule.steps, piece_mm)
        .map_err(|_| ClosedLoopError::Start(SteerError::BadConfig))?;
    let mut tracker = Tracker::new(conditions.faults, seed);
    let mut stop: Option<StopReason> = None;
    let mut predicted_miss_mm = None;
    let mut replan_evaluations = Vec::new();
    board.drive(piece_mm).map_err(ClosedLoopError::Controller)?;
    'pieces: while let Some(piece) = pieces.next_piece() {
        board.piece_ended().map_err(ClosedLoopError::Controller)?;
        let mut last = None;
        world.execute(&piece, |m| {
            last = Some(*m);
            ControlFlow::Continue(())
        });
        let Some(mut m) = last else { continue };
        (m.depth_mm, m.base_deg) = (pieces.depth_mm(), pieces.base_deg());
        for (reading, injected) in tracker.readings(&m) {
            let reply = board
                .update(&reading)
                .map_err(ClosedLoopError::Controller)?;
            if injected {
                continue; // the tracker's repeat or old reading: nothing new to act on
            }
            if reply.replanned {
                replan_evaluations.push(reply.evaluations);
            }
            match reply.command {
                Command::Continue => {}
                Command::Replace(s) => {
                    // Cannot fail: a continuation holds at most as many steps as the pieces.
                    let _ = pieces.replace(&s);
                }
                Command::Stop(reason) => {
                    stop = Some(reason);
                    predicted_miss_mm = Some(reply.predicted_error_mm).filter(|e| e.is_finite());
                    break 'pieces;
                }
            }
        }
    }
    let stats = board.stats().map_err(ClosedLoopError::Controller)?;
    let ended = Ended {
        stop,
        predicted_miss_mm,
        stats,
        replan_evaluations,
    };
    Ok(ended.run(&world, planned, seed))
}
