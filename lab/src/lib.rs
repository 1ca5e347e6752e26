//! The lab link: `needle steer` steering an insertion from an OpenIGTLink tracker stream and
//! commanding a robot, and what the simulated lab (`hil-sim --lab`) shares with it: the
//! OpenIGTLink frames and the registration ([`wire`]), the robot's text grammar ([`robot`]), the
//! tracker's state ([`tracker`]), the session and its interlocks ([`session`]), what 3D Slicer
//! is shown ([`slicer`], [`viewers`]), and the command itself ([`steer`]).
//!
//! A plan's schedule as the messages a robot is sent before it inserts (`needle steer` sends
//! these, then one step at a time as the tracker reports the tip):
//!
//! ```
//! use needle_lab::robot::{posture_command, step_list, RobotCommand};
//! use planner_core::execute::schedule::schedule;
//! use planner_core::Scenario;
//!
//! let scenario = Scenario::paper();
//! let report = planner_core::plan(&scenario)?;
//! let best = report.best().expect("the paper's scenario has a path");
//! let plan = schedule(&scenario, best).map_err(|e| anyhow::anyhow!("{e:?}"))?;
//! let mut messages = vec![posture_command(&plan.posture)];
//! messages.extend(step_list(&plan.steps));
//! messages.push(RobotCommand::Go);
//! assert_eq!(messages[1], RobotCommand::Steps { count: plan.steps.len() });
//! for m in &messages {
//!     // What the robot reads back is what was sent.
//!     assert_eq!(m.to_string().parse::<RobotCommand>()?, *m);
//! }
//! # Ok::<(), anyhow::Error>(())
//! ```

mod board;
pub mod fresh;
pub mod log;
pub mod outcome;
pub mod progress;
pub mod report;
pub mod robot;
pub mod session;
pub mod slicer;
pub mod sphere;
pub mod steer;
pub mod steer_setup;
pub mod tracker;
pub mod viewers;
pub mod wire;

pub use outcome::exit_code;
pub use steer::run_steer;
pub use steer_setup::SteerOptions;
