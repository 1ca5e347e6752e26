//! The needle driver's motion core: two axes, the schedule's moves as step trains, and the
//! safety state machine around them. `no_std`, no heap, no panics, no hardware: the board's
//! timer and pins, the QEMU board's simulated axes and the host's tests all drive the same code.
//!
//! - [`config`]: the axes in their units (insertion mm, rotation degrees), steps per unit,
//!   speed and acceleration limits, soft limits, the timer's tick rate.
//! - [`moves`]: a [`Move`] (planner-core's `Op`: rotate, insert, insert_spin, insert_duty)
//!   becomes coordinated segments, checked against the soft limits before any is queued.
//! - [`profile`] and [`runner`]: each segment becomes integer timer intervals, trapezoidal,
//!   both axes on the same profile shape; constant work per step, for the timer interrupt.
//! - [`safety`] and [`Controller`]: disarmed at power-up, homing against a switch, e-stop,
//!   limit switches, following error and the host link's watchdog; faults latch.
//! - [`step_clock`]: a board's step timer in integers (prescaler, the absolute schedule on a
//!   free-running counter, the clock, encoder counts), tested on the host.
//! - [`plant`]: simulated axes (inertia, missed steps, end switches, encoders); [`bench`]: the
//!   bench driver with them, as hil-sim and the QEMU board run it.
//!
//! The same moves give the same step train, bit for bit: the profile uses only correctly
//! rounded `f32` operations and integer ticks.
//!
//! ```
//! use needle_motion::{Controller, Inputs, Move, MotionConfig, Rates, SafetyConfig, State};
//!
//! let rates = Rates { insert_mm_s: 2.5, rotate_deg_s: 360.0, spin_rev_s: 4.0 };
//! let cfg = MotionConfig::bench(150.0, 360.0, rates);
//! let mut c = Controller::new(cfg, SafetyConfig::BENCH).unwrap();
//! // Power-up: disarmed, nothing moves.
//! assert!(c.execute(&[Move::Insert { length_mm: 1.0 }]).is_err());
//! c.arm().unwrap();
//! c.home().unwrap();
//! // The stage seeks its home switch; the switch closes: zero there, decelerate, come back.
//! for _ in 0..10 {
//!     c.next_step();
//! }
//! c.update(1, &Inputs { home: true, ..Inputs::default() });
//! while c.next_step().is_some() {}
//! assert_eq!((c.state(), c.steps()), (State::Armed, [0, 0]));
//! c.execute(&[
//!     Move::Rotate { angle_deg: 90.0 },
//!     Move::InsertSpin { length_mm: 2.0, turns: 2 },
//! ])
//! .unwrap();
//! let mut ticks = 0u64;
//! while let Some(event) = c.next_step() {
//!     ticks += u64::from(event.ticks);
//! }
//! // 2 mm at 1600 steps/mm; 90 degrees at 3200 steps a turn, the spin's turns undone.
//! assert_eq!(c.steps(), [3200, 800]);
//! assert_eq!(c.state(), State::Armed);
//! assert!(ticks > 0);
//! ```
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Two axes indexed alike in several arrays read best with explicit indices.
#![allow(clippy::needless_range_loop)]

pub mod bench;
pub mod check;
pub mod config;
mod controller;
mod error;
mod fields;
pub mod moves;
mod names;
pub mod plant;
pub mod profile;
pub mod runner;
pub mod safety;
pub mod step_clock;

pub use config::{AxisConfig, MotionConfig, Rates};
pub use controller::{Controller, Status, QUEUE};
pub use error::MotionError;
pub use fields::{Axis, ConfigField};
pub use moves::Move;
pub use runner::StepEvent;
pub use safety::{FaultCause, FaultRecord, Inputs, SafetyConfig, State};

#[cfg(test)]
mod testbench;
#[cfg(test)]
mod tests_inputs;
#[cfg(test)]
mod tests_moves;
#[cfg(test)]
mod tests_safety;
