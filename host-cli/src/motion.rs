//! `needle motion`: its flags, the board's axes driven by `needle_device::motion`.

use crate::link::LinkArgs;
use needle_device::motion::{Action, MotionOptions};
use std::path::PathBuf;

/// What to ask the board.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActionArg {
    /// The axes' status (also a heartbeat).
    Status,
    /// Allow motion (from disarmed).
    Arm,
    /// Forbid motion: both axes stop at once.
    Disarm,
    /// Seek the insertion stage's home switch, and wait until homed.
    Home,
    /// Plan SCENARIO here and execute its motor schedule, and wait until it is done.
    Move,
    /// Decelerate to rest, keeping the rest of the moves.
    Hold,
    /// Continue after a hold, and wait until done.
    Resume,
    /// Decelerate to rest and drop the moves.
    Stop,
    /// The e-stop: both axes stop at once; latched until cleared.
    Estop,
    /// End a latched fault whose cause is gone (disarmed, and unhomed unless the link was lost).
    ClearFault,
    /// Back to the power-up state (a latched fault stays).
    Reset,
}

impl From<ActionArg> for Action {
    fn from(a: ActionArg) -> Action {
        match a {
            ActionArg::Status => Action::Status,
            ActionArg::Arm => Action::Arm,
            ActionArg::Disarm => Action::Disarm,
            ActionArg::Home => Action::Home,
            ActionArg::Move => Action::Move,
            ActionArg::Hold => Action::Hold,
            ActionArg::Resume => Action::Resume,
            ActionArg::Stop => Action::Stop,
            ActionArg::Estop => Action::Estop,
            ActionArg::ClearFault => Action::ClearFault,
            ActionArg::Reset => Action::Reset,
        }
    }
}

/// `needle motion ACTION [SCENARIO]`.
#[derive(clap::Args, Debug)]
pub struct MotionArgs {
    /// What to ask the board.
    #[arg(value_enum)]
    action: ActionArg,
    /// The scenario whose plan `move` executes (planned here as `needle plan` plans it).
    #[arg(required_if_eq("action", "move"))]
    scenario: Option<PathBuf>,
    /// With `move`: the needle guide is set at the plan's tilt (this board only turns and
    /// inserts; a tilted plan is refused without it).
    #[arg(long)]
    tilt_set: bool,
    /// Print the final status as one JSON object.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    link: LinkArgs,
}

/// Runs `needle motion`.
pub fn motion(a: &MotionArgs) -> anyhow::Result<()> {
    needle_device::motion::motion(&MotionOptions {
        action: a.action.into(),
        scenario: a.scenario.clone(),
        tilt_set: a.tilt_set,
        json: a.json,
        link: a.link.options(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    /// The command line names each action as the library does, in the same order.
    #[test]
    fn the_flags_name_every_action_as_the_library() {
        let names = |a: ActionArg| a.to_possible_value().unwrap().get_name().to_string();
        let flags: Vec<(String, Action)> = ActionArg::value_variants()
            .iter()
            .map(|&a| (names(a), a.into()))
            .collect();
        let library: Vec<(String, Action)> = Action::ALL
            .iter()
            .map(|&a| (a.name().to_string(), a))
            .collect();
        assert_eq!(flags, library);
    }
}
