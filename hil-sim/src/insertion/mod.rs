//! The insertion simulator: the simulated robot, tissue and tracker of issue 9. A [`World`]
//! executes driver [`Step`](planner_core::execute::schedule::Step)s on a perturbed needle and
//! records the true tip path; [`open_loop`] runs a whole schedule; the [`Perturbation`] holds the
//! model's parameters with their literature-motivated defaults (docs/execution.md).
//!
//! A closed-loop controller drives the world step by step:
//!
//! ```
//! use hil_sim::insertion::{Perturbation, World};
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

mod closed;
mod perturbation;
mod run;
mod world;

pub use closed::{closed_loop, in_process, ClosedLoopError, ClosedRun, Controller, TrackerFaults};
pub use perturbation::{PerturbError, Perturbation, KEYS};
pub use run::{finish, open_loop, Planned, Run};
pub use world::{
    Drawn, Executed, Measurement, StepDraw, World, DRIFT_REFERENCE_MM, MAX_PIECE_MM, MIN_FACTOR,
};
