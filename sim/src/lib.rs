//! The insertion simulator: the simulated robot, tissue and tracker that execute a driver's motor
//! schedule on a perturbed needle, and the one seeded generator ([`random`]) they and the
//! host's analyses and tests draw from.
//!
//! A [`World`] executes driver [`Step`](planner_core::execute::schedule::Step)s on a perturbed
//! needle and records the true tip path; [`open_loop`] runs a whole schedule; [`closed_loop`]
//! lets a [`Controller`] (the in-process steering of `planner-core`, or anything that answers
//! tracker readings) replace the steps as the tracker reports the tip ([`closed_loop_observed`]
//! shows each answered reading with the true tip frame, and [`roll_trace`] the in-process
//! controller's roll error along a run); the [`Perturbation`] holds the model's parameters with
//! their literature-motivated defaults (docs/simulation.md), and the [`WorldEffects`] what the
//! planner's model leaves out (a 5-DOF sensor, field bias and registration error, layered
//! tissue, a pushed target, late imaging and tracking: all off by default,
//! [`World::with_effects`], [`open_loop_in`], [`closed_loop_in`]).
//!
//! What it is not: not a device and not a transport. The simulated *device* (the firmware's
//! request handler on a pty, TCP or in-process) is `hil-sim`; the link to a device is
//! `needle-link`. This crate depends on neither, so a closed loop steered by a device is an
//! adapter on the host side (`needle simulate --tcp|--port`, the device bench), and a change to
//! the protocol never rebuilds the simulator. Every figure it produces is simulated.
//!
//! A closed-loop controller drives the world step by step:
//!
//! ```
//! use needle_sim::{Perturbation, World};
//! use planner_core::execute::schedule::schedule;
//! use planner_core::{plan, Scenario};
//! use std::ops::ControlFlow;
//!
//! let scenario = Scenario::paper();
//! let best = plan(&scenario).unwrap().best().unwrap().clone();
//! let s = schedule(&scenario, &best).unwrap();
//! let mut world = World::new(&scenario, &s.posture, &Perturbation::default(), 7).unwrap();
//! let mut seen = 0;
//! for step in &s.steps {
//!     world.execute(step, |m| {
//!         seen += 1;
//!         // A controller would compare m.position with the plan here, and break off to re-steer.
//!         let _ = m.target;
//!         ControlFlow::Continue(())
//!     });
//! }
//! assert!(seen >= 90);
//! assert!((world.tip().p - world.true_target()).norm() < 10.0);
//! ```

#![forbid(unsafe_code)]
// The simulated world runs on the host only, where libm's kernels are not slow, and every
// simulated figure (goldens, the docs' accuracies) was made with their bits: the ban of
// clippy.toml (libm trigonometry outside planner-core's fmath) is for code the device runs.
#![allow(clippy::disallowed_methods)]

mod closed;
mod drawn;
mod driven;
pub mod effects;
mod executed;
mod factor;
mod faults;
mod layered;
mod measure;
mod outcome;
mod pieces;
pub mod random;
mod reach;
mod reading;
mod roll;
mod run;
mod world;

pub use closed::{
    closed_loop, closed_loop_in, closed_loop_observed, in_process, ClosedLoopError, ClosedRun,
    Conditions, Controller, Seen, Tracker,
};
pub use drawn::{Drawn, StepDraw};
pub use driven::{driven_loop, Board};
pub use effects::{
    EffectsError, LayerDepths, WorldEffects, LAYER_DEPTHS_KEY, TWICE_CLINICAL_FAULT_KEYS,
    TWICE_CLINICAL_KEYS, WORLD_KEYS,
};
pub use factor::MIN_FACTOR;
pub use faults::TrackerFaults;
pub use outcome::{controller_verdict, Outcome};
pub use planner_core::execute::perturbation::{
    PerturbError, Perturbation, DRIFT_REFERENCE_MM, KEYS, MAX_PIECE_MM, MEASURE_EVERY_MM_MIN,
};
pub use reach::nearest_reach;
pub use reading::Measurement;
pub use roll::{roll_error_deg, roll_trace, RollSample, RollSummary};
pub use run::{finish, open_loop, open_loop_in, Planned, Rotations, Run};
pub use world::{Executed, World, WorldError};
