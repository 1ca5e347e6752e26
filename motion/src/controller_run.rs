//! The controller's clock, inputs and step generation.

use super::{Controller, Current, Prepared};
use crate::config::Axis;
use crate::moves::SegmentTarget;
use crate::runner::{SegmentRun, StepEvent};
use crate::safety::{FaultCause, FaultRecord, Inputs, State};

/// Most segment set-ups one step may take: a move's zero-length segment (a duty cycle's held
/// push at duty 0), then each queued move could be empty. Bounded by the queue, never by the
/// schedule's length.
const MAX_SETUPS: usize = 2 * super::QUEUE + 2;

impl Controller {
    /// The clock (ms, wrapping) and the inputs: e-stop, switches and encoders are checked, the
    /// watchdog runs, homing ends at its switch, and the segment after the current one is set
    /// up ahead of the step interrupt. Returns the fault this call latched, if any.
    pub fn update(&mut self, now_ms: u32, inputs: &Inputs) -> Option<FaultRecord> {
        self.now_ms = now_ms;
        self.encoder = inputs.encoder;
        self.inputs = *inputs;
        if self.state == State::Faulted {
            return None;
        }
        if inputs.estop {
            return Some(self.fault(FaultCause::EStop));
        }
        if inputs.limit {
            return Some(self.fault(FaultCause::LimitSwitch));
        }
        if inputs.home {
            if self.state == State::Homing {
                if !self.homed {
                    self.homed_here(inputs);
                }
            } else if self.state != State::Disarmed && self.retracting() {
                return Some(self.fault(FaultCause::HomeSwitch));
            }
        }
        for axis in Axis::BOTH {
            let i = axis as usize;
            let Some(e) = inputs.encoder[i] else {
                continue;
            };
            let zero = *self.encoder_zero[i].get_or_insert(e.wrapping_sub(self.pos[i]));
            if e.wrapping_sub(zero).abs_diff(self.pos[i]) > self.safety.following_band[i] {
                return Some(self.fault(FaultCause::FollowingError(axis)));
            }
        }
        let fault = self.watchdog();
        self.prepare();
        fault
    }

    /// The e-stop's interrupt: both axes stop at once.
    pub fn estop(&mut self) -> FaultRecord {
        match (self.state, self.last_fault) {
            (State::Faulted, Some(f)) => f,
            _ => self.fault(FaultCause::EStop),
        }
    }

    fn watchdog(&mut self) -> Option<FaultRecord> {
        if !matches!(self.state, State::Moving | State::Holding | State::Homing) {
            return None;
        }
        let silent = self.now_ms.wrapping_sub(self.heard_ms);
        if silent >= self.safety.watchdog_stop_ms {
            return Some(self.fault(FaultCause::LinkLost));
        }
        if silent >= self.safety.watchdog_hold_ms && self.state != State::Holding {
            // A hold keeps the moves for a resume; a homing held is over (unhomed).
            self.run.stop();
            self.state = State::Holding;
            self.watchdog_hold = true;
        }
        None
    }

    /// Whether the insertion axis is stepping backwards.
    fn retracting(&self) -> bool {
        !self.run.is_done() && self.run.dir()[0] < 0 && self.run.steps_left()[0] > 0
    }

    /// The home switch closed: zero here, decelerate, then return to the zero.
    fn homed_here(&mut self, inputs: &Inputs) {
        self.pos = [0; 2];
        self.encoder_zero = inputs.encoder;
        self.homed = true;
        self.run.stop();
    }

    /// Homing's run ended: without the switch a fault; past it, back to the zero; there, armed.
    fn homing_done(&mut self) -> bool {
        if !self.homed {
            self.fault(FaultCause::HomingFailed);
            return false;
        }
        if self.pos[0] == 0 {
            self.state = State::Armed;
            self.since = [0; 2];
            return false;
        }
        let dist = self.cfg.to_units(Axis::Insertion, self.pos[0]);
        let seg = SegmentTarget {
            target: [0, self.pos[1]],
            rate: self.cfg.homing_mm_s / libm::fabsf(dist),
        };
        self.run = SegmentRun::new(&self.cfg, self.pos, &seg);
        true
    }

    /// Latch `cause`: both axes stop at once, the moves are dropped.
    pub(super) fn fault(&mut self, cause: FaultCause) -> FaultRecord {
        self.halt();
        let record = FaultRecord {
            cause,
            steps: self.pos,
            position: [0, 1].map(|i| self.cfg.to_units(Axis::BOTH[i], self.pos[i])),
            encoder: self.encoder,
            at_ms: self.now_ms,
        };
        self.last_fault = Some(record);
        self.state = State::Faulted;
        record
    }

    /// No further step: the segment, the move and the queue are dropped.
    pub(super) fn halt(&mut self) {
        self.run = SegmentRun::IDLE;
        self.queue.clear();
        self.current = None;
        self.speed = [0.0; 2];
        self.since = [0; 2];
    }

    /// The next step for the timer interrupt, `None` when there is none (at rest, disarmed,
    /// faulted). Bounded work: one event, at most [`MAX_SETUPS`] segment set-ups.
    pub fn next_step(&mut self) -> Option<StepEvent> {
        if !matches!(self.state, State::Moving | State::Holding | State::Homing) {
            return None;
        }
        for _ in 0..MAX_SETUPS {
            if let Some(e) = self.run.next_event() {
                self.account(&e);
                return Some(e);
            }
            if !self.next_segment() {
                break;
            }
        }
        self.speed = [0.0; 2];
        None
    }

    fn account(&mut self, e: &StepEvent) {
        let f = self.cfg.tick_hz as f32;
        for i in 0..2 {
            self.since[i] = self.since[i].saturating_add(e.ticks);
            if e.step[i] {
                self.pos[i] = self.pos[i].saturating_add(i32::from(e.dir[i]));
                self.speed[i] = f32::from(e.dir[i]) * f / self.since[i].max(1) as f32;
                self.since[i] = 0;
            }
        }
    }

    /// Sets up the segment after the current one while the axes move, so that the step
    /// interrupt only swaps it in: the set-up (the schedule's arithmetic, in `f64`) is the
    /// costliest step otherwise. The same set-up as [`Self::next_step`] would make, used only
    /// when the move, part and start it was made for are the ones met.
    // One copy for its two callers (`update`, `execute`).
    #[inline(never)]
    pub(super) fn prepare(&mut self) {
        if self.state != State::Moving || self.prepared.is_some() {
            return;
        }
        // After the current segment, or the first of the queue before any.
        let (mv, part, from) = match (self.current, self.queue.front()) {
            (Some(c), _) if c.part + 1 < c.mv.parts() => (c.mv, c.part + 1, c.seg.target),
            (Some(c), Some(&mv)) => (mv, 0, c.seg.target),
            (None, Some(&mv)) if self.run.is_done() => (mv, 0, self.pos),
            _ => return,
        };
        let seg = mv.segment(&self.cfg, part);
        let run = SegmentRun::new(&self.cfg, from, &seg);
        self.prepared = Some(Prepared {
            mv,
            part,
            from,
            seg,
            run,
        });
    }

    /// Set up the next segment; `false` when there is none (then the state settles).
    fn next_segment(&mut self) -> bool {
        match self.state {
            State::Homing => return self.homing_done(),
            State::Holding => return false,
            _ => {}
        }
        let next = match self.current {
            Some(c) if c.part + 1 < c.mv.parts() => Some((c.mv, c.part + 1)),
            _ => self.queue.pop_front().map(|mv| (mv, 0)),
        };
        let Some((mv, part)) = next else {
            self.current = None;
            self.state = State::Armed;
            self.since = [0; 2];
            return false;
        };
        let (seg, run) = match self.prepared.take() {
            Some(p) if (p.mv, p.part, p.from) == (mv, part, self.pos) => (p.seg, p.run),
            _ => {
                let seg = mv.segment(&self.cfg, part);
                (seg, SegmentRun::new(&self.cfg, self.pos, &seg))
            }
        };
        self.current = Some(Current { mv, part, seg });
        self.run = run;
        true
    }
}
