//! The device budgets: what the firmware may cost on the microcontroller, in one table.
//!
//! `cargo xtask device-bench --check` enforces them ([`breaches`]), `cargo xtask device-bench --budgets`
//! prints them ([`markdown_table`], the table docs/firmware.md shows, checked against it by a
//! test), and the firmware tests read them from here. The check is a pure function of the
//! measured figures, so it is tested without QEMU.

use crate::figures::BoardFigures;
use anyhow::{bail, Result};
use std::fmt;

/// The figure of one board a budget limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Flash bytes of the image (`flash_bytes`).
    Flash,
    /// Static RAM plus the peak stack, in bytes (`static_ram_bytes + peak_stack_bytes`).
    Ram,
    /// Instructions of one plan of `examples/paper.toml` (`instructions.paper`).
    PaperPlan,
    /// Instructions of one plan of `devtools/workloads/space.toml`, the 3-D example planned
    /// unbounded (`instructions.space`).
    SpacePlan,
    /// Instructions of one plan of `examples/paper-bounded.toml`, the paper's scenario under a
    /// 1 % collision bound for a steered insertion (`instructions.paper-bounded`).
    BoundedPaperPlan,
    /// Instructions of one plan of `examples/spheres256.toml`, the device's full 256 spheres,
    /// 32 of them near the path (`instructions.spheres256`).
    SpheresPlan,
    /// Most instructions of one steering reading, over every steered scenario
    /// (`replan_instructions.*.max`).
    SteeringReading,
    /// Most instructions of one step of the motion core (`step_instructions.max`), on a board
    /// that drives axes.
    StepInterrupt,
    /// Most instructions of one move request of the paper's schedule
    /// (`step_instructions.move_request`), on a board that drives axes.
    MoveRequest,
}

/// How a budget's figure is counted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// Bytes.
    Bytes,
    /// Guest instructions, counted exactly by the QEMU plugin.
    Instructions,
}

/// One limit the firmware must stay within on every board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// What the budget limits, as messages name it.
    pub name: &'static str,
    /// Which figure it reads.
    pub quantity: Quantity,
    /// The unit of `limit`.
    pub unit: Unit,
    /// The largest figure allowed (inclusive).
    pub limit: u64,
    /// What staying within it protects.
    pub protects: &'static str,
}

/// The device budgets. One instruction per cycle at the stm32f4's 168 MHz turns instructions
/// into time (a lower bound: flash wait states make an M4F average somewhat more).
pub const BUDGETS: &[Budget] = &[
    Budget {
        name: "flash",
        quantity: Quantity::Flash,
        unit: Unit::Bytes,
        limit: 256 * 1024,
        protects:
            "the image, USB variant included, fits the 256 KiB Cortex-M4F parts (STM32F401RC, \
                   STM32F411RC), not only the STM32F405's 1 MiB",
    },
    Budget {
        name: "RAM (static + peak stack)",
        quantity: Quantity::Ram,
        unit: Unit::Bytes,
        limit: 60 * 1024,
        protects:
            "the firmware holds 256 spheres in 60 KiB of SRAM (an STM32F401RC's 64 KiB, 4 KiB \
                   left to the driver's own code), with no heap to run out of",
    },
    Budget {
        name: "paper plan",
        quantity: Quantity::PaperPlan,
        unit: Unit::Instructions,
        limit: 15_000_000,
        protects:
            "a plan of the paper's scenario in about 0.09 s at 168 MHz, before the needle moves",
    },
    Budget {
        name: "space plan",
        quantity: Quantity::SpacePlan,
        unit: Unit::Instructions,
        limit: 100_000_000,
        protects: "a 3-D plan among five spheres in about 0.6 s at 168 MHz",
    },
    Budget {
        name: "bounded paper plan",
        quantity: Quantity::BoundedPaperPlan,
        unit: Unit::Instructions,
        limit: 40_000_000,
        protects: "a plan of the paper's scenario under a 1 % collision bound (two rounds of \
                   every form, and the spread of each round's plan) in about 0.24 s at 168 MHz",
    },
    Budget {
        name: "256-sphere plan",
        quantity: Quantity::SpheresPlan,
        unit: Unit::Instructions,
        limit: 400_000_000,
        protects: "a plan among the device's full 256 spheres (32 of them within 20 mm of the \
                   path, `planner.risk_within_mm = 20`) in about 2.4 s at 168 MHz",
    },
    Budget {
        name: "steering reading",
        quantity: Quantity::SteeringReading,
        unit: Unit::Instructions,
        limit: 1_000_000,
        protects:
            "each tracker reading answered (estimate, and a replan when needed) in about 6 ms \
                   at 168 MHz: a quarter of the 25 ms between a 40 Hz tracker's readings",
    },
    Budget {
        name: "step interrupt",
        quantity: Quantity::StepInterrupt,
        unit: Unit::Instructions,
        limit: 2_000,
        protects: "each step of either axis computed in about 12 µs at 168 MHz, which leaves \
                   room for 30 kHz step rates on a board that drives axes",
    },
    Budget {
        name: "move request",
        quantity: Quantity::MoveRequest,
        unit: Unit::Instructions,
        limit: 200_000,
        protects: "a schedule's move request (every move checked against the soft limits and \
                   queued, the first segment set up) answered in about 1.2 ms at 168 MHz, under \
                   the link watchdog's 200 ms by far",
    },
];

impl Unit {
    /// `n` of this unit, for people: bytes with KiB, instructions with millions.
    pub fn show(self, n: u64) -> String {
        // Whole KiB and whole millions are shown whole (a remainder test, not `is_multiple_of`,
        // which is newer than the workspace's Rust 1.85).
        match self {
            Unit::Bytes => match (n / 1024, n % 1024) {
                (kib, 0) => format!("{n} B ({kib} KiB)"),
                _ => format!("{n} B ({:.1} KiB)", n as f64 / 1024.0),
            },
            Unit::Instructions => match (n / 1_000_000, n % 1_000_000) {
                (0, _) => format!("{n} instructions"),
                (millions, 0) => format!("{millions} M instructions"),
                _ => format!("{n} instructions ({:.2} M)", n as f64 / 1e6),
            },
        }
    }
}

impl Budget {
    /// The board's figure for this budget; `None` when the run did not measure it (the paper or
    /// space scenario not among the files, steering left out).
    pub fn figure(&self, board: &BoardFigures) -> Option<u64> {
        let plan = |name: &str| {
            board
                .instructions
                .iter()
                .find(|(scenario, _)| scenario == name)
                .map(|&(_, n)| n)
        };
        match self.quantity {
            Quantity::Flash => Some(board.flash_bytes),
            Quantity::Ram => Some(board.static_ram_bytes + board.peak_stack_bytes),
            Quantity::PaperPlan => plan("paper"),
            Quantity::SpacePlan => plan("space"),
            Quantity::BoundedPaperPlan => plan("paper-bounded"),
            Quantity::SpheresPlan => plan("spheres256"),
            Quantity::SteeringReading => board.replan_instructions.iter().map(|(_, r)| r.max).max(),
            Quantity::StepInterrupt => board.steps.map(|s| s.max),
            Quantity::MoveRequest => board.steps.map(|s| s.move_request),
        }
    }

    /// Whether the budget holds for the board: the step interrupt's and the move request's
    /// only where it drives axes.
    pub fn applies(&self, board: &BoardFigures) -> bool {
        let motion = matches!(
            self.quantity,
            Quantity::StepInterrupt | Quantity::MoveRequest
        );
        !motion || board.steps.is_some()
    }
}

/// A budget a board did not keep.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Breach {
    /// The board.
    pub board: String,
    /// The budget.
    pub budget: &'static Budget,
    /// Its figure, or `None` when it was not measured (a budget that cannot be checked fails).
    pub figure: Option<u64>,
}

impl fmt::Display for Breach {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.budget;
        match self.figure {
            Some(n) => write!(
                f,
                "{}: {} over budget: {} > {} ({})",
                self.board,
                b.name,
                b.unit.show(n),
                b.unit.show(b.limit),
                b.protects
            ),
            None => write!(
                f,
                "{}: {} not measured, so its budget of {} cannot be checked (measure \
                 examples/paper.toml, space.toml, paper-bounded.toml and spheres256.toml, with \
                 steering)",
                self.board,
                b.name,
                b.unit.show(b.limit)
            ),
        }
    }
}

/// Every budget of [`BUDGETS`] the board's figures leave, or cannot show kept.
pub fn breaches(board: &BoardFigures) -> Vec<Breach> {
    BUDGETS
        .iter()
        .filter(|budget| budget.applies(board))
        .filter_map(|budget| {
            let figure = budget.figure(board);
            figure.is_none_or(|n| n > budget.limit).then(|| Breach {
                board: board.board.clone(),
                budget,
                figure,
            })
        })
        .collect()
}

/// The lines around the budgets table in docs/firmware.md.
pub const DOC_MARKERS: (&str, &str) = (
    "<!-- `cargo xtask device-bench --budgets` prints this table; a test compares them -->",
    "<!-- end of the budgets table -->",
);

/// The budgets as a Markdown table (`cargo xtask device-bench --budgets`, docs/firmware.md).
pub fn markdown_table() -> String {
    let mut s = String::from("| budget | at most | protects |\n| --- | --- | --- |\n");
    for b in BUDGETS {
        s.push_str(&format!(
            "| {} | {} | {} |\n",
            b.name,
            b.unit.show(b.limit),
            b.protects
        ));
    }
    s
}

/// What `--check` refuses, as sentences: every budget of [`BUDGETS`] left (or not
/// measured), and every device plan that differs from the host's. Empty when all is well.
pub fn problems(figures: &BoardFigures) -> Vec<String> {
    let mut out: Vec<String> = breaches(figures).iter().map(ToString::to_string).collect();
    for (name, same) in &figures.matches_host {
        if !same {
            out.push(format!(
                "{}: the device's plan of {name} differs from the host's",
                figures.board
            ));
        }
    }
    out
}

/// What the measured figures come to: with `check`, an error listing every problem (so
/// `cargo xtask device-bench --check` exits non-zero on any), else the problems, to print as warnings.
pub fn verdict(figures: &[BoardFigures], check: bool) -> Result<Vec<String>> {
    let problems: Vec<String> = figures.iter().flat_map(problems).collect();
    if check && !problems.is_empty() {
        bail!(
            "{} check(s) failed:\n  {}",
            problems.len(),
            problems.join("\n  ")
        );
    }
    Ok(problems)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::replan_bench::ReplanFigures;
    use crate::step_bench::StepFigures;

    #[test]
    fn check_refuses_a_300_kib_image_and_without_it_warns() {
        let mut big = within();
        big.flash_bytes = 300 * 1024;
        let all = [within(), big];
        let error = verdict(&all, true).unwrap_err().to_string();
        assert!(
            error.starts_with("1 check(s) failed:\n  stm32f4: flash over budget: 307200 B"),
            "{error}"
        );
        assert_eq!(verdict(&all, false).unwrap().len(), 1);
        assert_eq!(verdict(&all[..1], true).unwrap(), Vec::<String>::new());
    }

    #[test]
    fn a_device_plan_that_differs_from_the_hosts_is_a_problem() {
        let mut figures = within();
        figures.matches_host[2].1 = false;
        assert_eq!(
            problems(&figures),
            ["stm32f4: the device's plan of space differs from the host's"]
        );
    }

    /// The figures measured on the stm32f4 (`cargo xtask device-bench --json`), within every budget.
    pub(crate) fn within() -> BoardFigures {
        BoardFigures {
            board: "stm32f4".into(),
            flash_bytes: 174_980,
            static_ram_bytes: 33_436,
            peak_stack_bytes: 23_320,
            // In the JSON's order (its keys sorted).
            instructions: vec![
                ("paper".into(), 14_321_527),
                ("paper-bounded".into(), 34_680_528),
                ("space".into(), 86_243_706),
                ("spheres256".into(), 279_855_789),
            ],
            matches_host: vec![
                ("paper".into(), true),
                ("paper-bounded".into(), true),
                ("space".into(), true),
                ("spheres256".into(), true),
            ],
            replan_instructions: ["paper", "space"]
                .iter()
                .zip([408_953, 337_696])
                .map(|(name, max)| {
                    let r = ReplanFigures {
                        readings: 537,
                        replans: 410,
                        max,
                        median: 74_090,
                    };
                    (name.to_string(), r)
                })
                .collect(),
            steps: Some(StepFigures {
                steps: 163_000,
                max: 900,
                sum: 97_800_000,
                move_request: 30_000,
            }),
        }
    }

    /// The figures with `quantity`'s one more than its budget allows.
    fn over(quantity: Quantity) -> BoardFigures {
        let mut f = within();
        let budget = BUDGETS.iter().find(|b| b.quantity == quantity).unwrap();
        let above = budget.limit + 1;
        match quantity {
            Quantity::Flash => f.flash_bytes = above,
            Quantity::Ram => f.peak_stack_bytes = above - f.static_ram_bytes,
            Quantity::PaperPlan => f.instructions[0].1 = above,
            Quantity::BoundedPaperPlan => f.instructions[1].1 = above,
            Quantity::SpacePlan => f.instructions[2].1 = above,
            Quantity::SpheresPlan => f.instructions[3].1 = above,
            Quantity::SteeringReading => f.replan_instructions[1].1.max = above,
            Quantity::StepInterrupt => f.steps.as_mut().unwrap().max = above,
            Quantity::MoveRequest => f.steps.as_mut().unwrap().move_request = above,
        }
        f
    }

    #[test]
    fn figures_within_every_budget_pass() {
        assert_eq!(breaches(&within()), []);
        // A figure equal to its limit is within it.
        let mut f = within();
        f.flash_bytes = 256 * 1024;
        assert_eq!(breaches(&f), []);
    }

    #[test]
    fn each_budget_exceeded_alone_fails_naming_that_budget() {
        let quantities = [
            Quantity::Flash,
            Quantity::Ram,
            Quantity::PaperPlan,
            Quantity::SpacePlan,
            Quantity::BoundedPaperPlan,
            Quantity::SpheresPlan,
            Quantity::SteeringReading,
            Quantity::StepInterrupt,
            Quantity::MoveRequest,
        ];
        assert_eq!(quantities.len(), BUDGETS.len(), "a budget left untested");
        for quantity in quantities {
            let found = breaches(&over(quantity));
            assert_eq!(found.len(), 1, "{quantity:?}: {found:?}");
            let breach = &found[0];
            assert_eq!(breach.budget.quantity, quantity);
            let message = breach.to_string();
            assert!(
                message.starts_with(&format!("stm32f4: {} over budget: ", breach.budget.name)),
                "{message}"
            );
            assert!(
                message.contains(&breach.budget.unit.show(breach.budget.limit)),
                "{message}"
            );
        }
    }

    #[test]
    fn a_board_without_axes_has_no_step_budget_to_keep() {
        let mut f = within();
        f.steps = None;
        assert_eq!(breaches(&f), []);
    }

    #[test]
    fn a_budget_left_unmeasured_fails_rather_than_passes() {
        let mut f = within();
        f.instructions.retain(|(name, _)| name != "space");
        f.replan_instructions.clear();
        let names: Vec<&str> = breaches(&f).iter().map(|b| b.budget.name).collect();
        assert_eq!(names, ["space plan", "steering reading"]);
        assert!(breaches(&f)[0].to_string().contains("not measured"));
    }

    #[test]
    fn the_firmware_doc_shows_this_table() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/firmware.md");
        let doc = std::fs::read_to_string(path).expect("docs/firmware.md");
        let (begin, end) = DOC_MARKERS;
        let block = doc
            .split_once(begin)
            .and_then(|(_, rest)| rest.split_once(end))
            .map(|(block, _)| block.trim_start_matches('\n'));
        assert_eq!(
            block,
            Some(markdown_table().as_str()),
            "docs/firmware.md's budgets table differs from `cargo xtask device-bench --budgets`: \
             paste its output between {begin} and {end}"
        );
    }

    #[test]
    fn limits_are_shown_in_their_unit() {
        assert_eq!(Unit::Bytes.show(131_072), "131072 B (128 KiB)");
        assert_eq!(Unit::Bytes.show(127_496), "127496 B (124.5 KiB)");
        assert_eq!(Unit::Instructions.show(15_000_000), "15 M instructions");
        assert_eq!(Unit::Instructions.show(2_000), "2000 instructions");
        assert_eq!(
            Unit::Instructions.show(13_704_929),
            "13704929 instructions (13.70 M)"
        );
    }
}
