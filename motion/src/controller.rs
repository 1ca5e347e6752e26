//! The controller: the safety state machine around the move queue and the step generator.
//!
//! Requests ([`Controller::arm`], [`Controller::execute`], ...) come from the main loop, the
//! inputs and the clock through [`Controller::update`], and the timer interrupt calls
//! [`Controller::next_step`] for each step. A fault stops both axes at once: from the call that
//! sees it, `next_step` gives no further step.

use crate::config::{Axis, MotionConfig, Rates};
use crate::moves::{Move, Planned, Resolved, SegmentTarget};
use crate::runner::SegmentRun;
use crate::safety::{FaultCause, FaultRecord, Inputs, SafetyConfig, State};
use crate::MotionError;

/// Moves the controller holds at once: a schedule's (at most two per segment of a plan of
/// control degree four) with room for a continuation.
pub const QUEUE: usize = 16;

/// The move being executed and its segment.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Current {
    mv: Resolved,
    part: u32,
    seg: SegmentTarget,
}

/// The segment after the current one, set up ahead of time outside the step interrupt
/// ([`Controller::update`]), with what it was set up for.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Prepared {
    mv: Resolved,
    part: u32,
    /// Where the current segment ends: the new one's start.
    from: [i32; 2],
    seg: SegmentTarget,
    run: SegmentRun,
}

/// What the controller reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    /// State.
    pub state: State,
    /// Whether the axes are homed.
    pub homed: bool,
    /// Commanded positions (steps, [`Axis`] order).
    pub steps: [i32; 2],
    /// The same in units (mm, degrees).
    pub position: [f32; 2],
    /// Speeds over the last step (units/s, signed; 0 at rest).
    pub speed: [f32; 2],
    /// Moves not yet finished.
    pub moves_left: u8,
    /// The latched fault, or the last one cleared.
    pub last_fault: Option<FaultRecord>,
}

/// The motion core of one driver.
#[derive(Clone, Debug)]
pub struct Controller {
    cfg: MotionConfig,
    safety: SafetyConfig,
    state: State,
    homed: bool,
    last_fault: Option<FaultRecord>,
    pos: [i32; 2],
    planned: Planned,
    queue: heapless::Deque<Resolved, QUEUE>,
    current: Option<Current>,
    run: SegmentRun,
    /// The next segment, set up ahead (dropped whenever the plan or the settings change).
    prepared: Option<Prepared>,
    /// Ticks since each axis' last step, and the speed it gave (steps/s, signed).
    since: [u32; 2],
    speed: [f32; 2],
    now_ms: u32,
    heard_ms: u32,
    /// Whether the watchdog made the current hold.
    watchdog_hold: bool,
    encoder: [Option<i32>; 2],
    /// The inputs as last read.
    inputs: Inputs,
    /// The encoder reading at commanded position zero (an incremental encoder counts from
    /// wherever it powered up; set at the first reading, again at homing and after a fault).
    encoder_zero: [Option<i32>; 2],
}

impl Controller {
    /// A controller at power-up: disarmed, not homed, at position zero.
    pub fn new(cfg: MotionConfig, safety: SafetyConfig) -> Result<Controller, MotionError> {
        cfg.validate()?;
        if safety.watchdog_stop_ms <= safety.watchdog_hold_ms {
            return Err(MotionError::Config(crate::ConfigField::Rate));
        }
        Ok(Controller {
            cfg,
            safety,
            state: State::Disarmed,
            homed: false,
            last_fault: None,
            pos: [0; 2],
            planned: Planned { at: [0.0; 2] },
            queue: heapless::Deque::new(),
            current: None,
            run: SegmentRun::IDLE,
            prepared: None,
            since: [0; 2],
            speed: [0.0; 2],
            now_ms: 0,
            heard_ms: 0,
            watchdog_hold: false,
            encoder: [None; 2],
            inputs: Inputs {
                estop: false,
                limit: false,
                home: false,
                encoder: [None; 2],
            },
            encoder_zero: [None; 2],
        })
    }

    /// The configuration.
    pub fn config(&self) -> &MotionConfig {
        &self.cfg
    }

    /// Take a plan's rates and soft limits (insertion from 0 to the needle's length `needle_mm`,
    /// twist within ±`max_twist_deg`): at rest only, disarmed or armed with nothing queued.
    pub fn set_job(
        &mut self,
        rates: Rates,
        needle_mm: f32,
        max_twist_deg: f32,
    ) -> Result<(), MotionError> {
        self.set_job_about(rates, needle_mm, max_twist_deg, 0.0)
    }

    /// [`Controller::set_job`] with the twist counted from the shaft at `zero_twist_deg` (the
    /// roll it was turned to before the insertion): the rotation within `zero_twist_deg` ±
    /// `max_twist_deg`, spins starting towards it.
    pub fn set_job_about(
        &mut self,
        rates: Rates,
        needle_mm: f32,
        max_twist_deg: f32,
        zero_twist_deg: f32,
    ) -> Result<(), MotionError> {
        self.refuse_if_faulted()?;
        if !matches!(self.state, State::Disarmed | State::Armed) {
            return Err(MotionError::NotAllowed(self.state));
        }
        let mut cfg = self.cfg;
        cfg.rates = rates;
        (cfg.axes[0].min, cfg.axes[0].max) = (0.0, needle_mm);
        (cfg.axes[1].min, cfg.axes[1].max) = (
            zero_twist_deg - max_twist_deg,
            zero_twist_deg + max_twist_deg,
        );
        cfg.validate()?;
        self.cfg = cfg;
        self.prepared = None;
        Ok(())
    }

    /// The state.
    pub fn state(&self) -> State {
        self.state
    }

    /// The inputs as [`Controller::update`] last read them (for a request from afar, such as
    /// clearing a fault).
    pub fn inputs(&self) -> Inputs {
        self.inputs
    }

    /// Commanded positions (steps).
    pub fn steps(&self) -> [i32; 2] {
        self.pos
    }

    /// Everything the host is told.
    pub fn status(&self) -> Status {
        Status {
            state: self.state,
            homed: self.homed,
            steps: self.pos,
            position: [0, 1].map(|i| self.cfg.to_units(Axis::BOTH[i], self.pos[i])),
            speed: [0, 1].map(|i| self.speed[i] / self.cfg.axes[i].steps_per_unit),
            moves_left: (self.queue.len() + usize::from(self.current.is_some())) as u8,
            last_fault: self.last_fault,
        }
    }

    fn refuse_if_faulted(&self) -> Result<(), MotionError> {
        match (self.state, self.last_fault) {
            (State::Faulted, Some(f)) => Err(MotionError::Faulted(f.cause)),
            _ => Ok(()),
        }
    }

    /// Allow motion: from `Disarmed` only.
    pub fn arm(&mut self) -> Result<(), MotionError> {
        self.refuse_if_faulted()?;
        match self.state {
            State::Disarmed => {
                self.state = State::Armed;
                Ok(())
            }
            State::Armed => Ok(()),
            s => Err(MotionError::NotAllowed(s)),
        }
    }

    /// Forbid motion: both axes stop at once, the moves are dropped. A fault stays latched.
    pub fn disarm(&mut self) -> Result<(), MotionError> {
        self.refuse_if_faulted()?;
        self.halt();
        self.state = State::Disarmed;
        Ok(())
    }

    /// A reset request: back to the power-up state (disarmed, not homed), unless a fault is
    /// latched, which only [`Controller::clear_fault`] ends.
    pub fn reset(&mut self) -> Result<(), MotionError> {
        self.disarm()?;
        self.homed = false;
        Ok(())
    }

    /// Seek the home switch with the insertion stage (armed, at rest). The rotation's zero is
    /// where the shaft is when the switch is met.
    pub fn home(&mut self) -> Result<(), MotionError> {
        self.refuse_if_faulted()?;
        if self.state != State::Armed {
            return Err(MotionError::NotAllowed(self.state));
        }
        let back = self
            .cfg
            .to_steps(Axis::Insertion, -f64::from(self.cfg.homing_travel_mm));
        let seg = SegmentTarget {
            target: [self.pos[0].saturating_add(back), self.pos[1]],
            rate: self.cfg.homing_mm_s / self.cfg.homing_travel_mm,
        };
        self.homed = false;
        self.run = SegmentRun::new(&self.cfg, self.pos, &seg);
        self.state = State::Homing;
        self.heard_ms = self.now_ms;
        Ok(())
    }

    /// Execute `moves` in order (armed, homed, at rest with nothing queued). All of them are
    /// checked against the soft limits first: on any error none is queued.
    pub fn execute(&mut self, moves: &[Move]) -> Result<(), MotionError> {
        self.refuse_if_faulted()?;
        if self.state != State::Armed {
            return Err(MotionError::NotAllowed(self.state));
        }
        if !self.homed {
            return Err(MotionError::NotHomed);
        }
        if moves.len() > QUEUE {
            return Err(MotionError::QueueFull);
        }
        let mut planned = Planned {
            at: [0, 1].map(|i| f64::from(self.cfg.to_units(Axis::BOTH[i], self.pos[i]))),
        };
        let mut queue = heapless::Deque::new();
        for &mv in moves {
            let r = planned.resolve(&self.cfg, mv)?;
            queue.push_back(r).map_err(|_| MotionError::QueueFull)?;
        }
        self.planned = planned;
        self.queue = queue;
        self.prepared = None;
        self.state = State::Moving;
        self.heard_ms = self.now_ms;
        // The first segment now, not in the step interrupt.
        self.prepare();
        Ok(())
    }

    /// Decelerate to rest and keep the rest of the moves for [`Controller::resume`].
    pub fn hold(&mut self) -> Result<(), MotionError> {
        self.refuse_if_faulted()?;
        match self.state {
            State::Moving => {
                self.run.stop();
                self.state = State::Holding;
                self.watchdog_hold = false;
                Ok(())
            }
            State::Holding => Ok(()),
            s => Err(MotionError::NotAllowed(s)),
        }
    }

    /// Continue a hold once at rest: the interrupted segment goes on to its target.
    pub fn resume(&mut self) -> Result<(), MotionError> {
        self.refuse_if_faulted()?;
        if self.state != State::Holding || !self.run.is_done() {
            return Err(MotionError::NotAllowed(self.state));
        }
        if let Some(c) = self.current {
            self.run = SegmentRun::new(&self.cfg, self.pos, &c.seg);
        }
        self.state = State::Moving;
        self.watchdog_hold = false;
        self.heard_ms = self.now_ms;
        Ok(())
    }

    /// Decelerate to rest and drop the moves; armed at rest afterwards.
    pub fn stop(&mut self) -> Result<(), MotionError> {
        self.refuse_if_faulted()?;
        match self.state {
            State::Moving | State::Holding | State::Homing => {
                self.queue.clear();
                self.current = None;
                self.run.stop();
                // Moving with nothing queued: armed once at rest (a stopped homing unhomed).
                self.state = State::Moving;
                Ok(())
            }
            State::Armed | State::Disarmed => Ok(()),
            State::Faulted => Err(MotionError::NotAllowed(State::Faulted)),
        }
    }

    /// End a latched fault once its cause is gone: disarmed, and not homed unless the fault
    /// left the axes where they were commanded (a lost link stops them under control).
    pub fn clear_fault(&mut self, inputs: &Inputs) -> Result<(), MotionError> {
        let Some(fault) = self.last_fault.filter(|_| self.state == State::Faulted) else {
            return Ok(());
        };
        let active = match fault.cause {
            FaultCause::EStop => inputs.estop,
            FaultCause::LimitSwitch => inputs.limit,
            _ => false,
        };
        if active || inputs.estop {
            return Err(MotionError::CauseActive(fault.cause));
        }
        self.homed &= fault.cause == FaultCause::LinkLost;
        self.encoder_zero = [None; 2];
        self.state = State::Disarmed;
        Ok(())
    }

    /// A reading or heartbeat from the host: the link watchdog starts again.
    pub fn heartbeat(&mut self) {
        self.heard_ms = self.now_ms;
    }
}

#[path = "controller_run.rs"]
mod run;
