//! `cargo xtask device-bench`: what the planner costs on the microcontroller, measured in QEMU.
//!
//! For each board it builds the release firmware, reads flash and static RAM from the image,
//! boots it in QEMU (mps2-an386 for the `mps2-an386` build, netduinoplus2 for the `stm32f4`
//! build) with the instruction-count plugin (`tools/insn-count`), plans each scenario over the
//! emulated UART, steers, moves the axes of a board that drives them (the step interrupt), and
//! reads the stack's high-water mark from the painted stack at the end. Each device plan is also
//! checked against the host's plan, bit for bit.

use crate::firmware_artifacts::{self as artifacts, ensure_qemu, ensure_target};
use crate::replan_bench::Steered;
use crate::{budgets, elf, profile, qemu};
// The figures and their verdict live in `figures`; here they are measured.
pub use crate::budgets::verdict;
pub use crate::figures::{table, BoardFigures};
use anyhow::{bail, Context, Result};
use needle_link::{Client, ClientConfig};
use planner_core::wire::{ChanceRequest, PlanResult};
use planner_core::Scenario;
use serde_json::Value;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The value cortex-m-rt paints the stack with at reset (feature `paint-stack`).
const STACK_PAINT: u32 = 0xCCCC_CCCC;

/// The link to the emulated board: every answer within 5 s, and no request repeated (a repeat
/// that reached the device while it plans would be counted, so the measurement fails instead).
const LINK: ClientConfig = ClientConfig {
    timeout: Duration::from_secs(5),
    retries: 0,
    deadline: None,
};

/// Longest silence while the device plans (the client asks nothing meanwhile: a status query
/// would be counted). Generous: a form takes well under a second in QEMU, so only a stuck
/// board waits this long.
const PLAN_SILENCE: Duration = Duration::from_secs(600);

/// A board build and the QEMU machine that runs it.
pub struct Board {
    /// Name in the report.
    pub name: &'static str,
    /// Cargo features of the firmware build.
    pub features: &'static str,
    /// QEMU machine.
    pub machine: &'static str,
    /// Whether its axes move in QEMU (the step interrupt is measured). The stm32f4's do not:
    /// netduinoplus2 models neither the timers' compare interrupts its steps come from nor the
    /// GPIO its switches are read on.
    pub moves_in_qemu: bool,
}

/// The boards measured.
pub const BOARDS: [Board; 2] = [
    Board {
        name: "mps2-an386",
        features: "mps2-an386",
        machine: "mps2-an386",
        moves_in_qemu: true,
    },
    Board {
        name: "stm32f4",
        features: "stm32f4",
        machine: "netduinoplus2",
        moves_in_qemu: false,
    },
];

/// A scenario to plan: its name (file stem) and contents.
pub struct NamedScenario {
    /// File stem, the key in `instructions`.
    pub name: String,
    /// The scenario.
    pub scenario: Scenario,
    /// The collision bound it is planned under, if its file sets one.
    pub chance: Option<ChanceRequest>,
}

/// Reads a scenario file and its collision bound (`needle`'s TOML reader; passed in, since this
/// crate sits below the host crates).
pub type LoadScenario<'a> = &'a dyn Fn(&Path) -> Result<(Scenario, Option<ChanceRequest>)>;

/// Loads scenario files with `load`, named by their stem.
pub fn load_scenarios(files: &[PathBuf], load: LoadScenario) -> Result<Vec<NamedScenario>> {
    files
        .iter()
        .map(|f| {
            let name = f
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("scenario")
                .to_owned();
            let (scenario, chance) = load(f)?;
            Ok(NamedScenario {
                name,
                scenario,
                chance,
            })
        })
        .collect()
}

fn encoded(result: &PlanResult) -> Result<Vec<u8>> {
    let mut buf = vec![0u8; planner_core::wire::MAX_PLAN_RESULT];
    Ok(postcard::to_slice(result, &mut buf)
        .context("encoding a plan")?
        .to_vec())
}

/// The curvature reserve a plan for a steered insertion keeps when its file says nothing of it
/// (`needle`'s `CLOSED_LOOP_CURVATURE_RESERVE`, in the crate above this one).
const STEERED_RESERVE: f32 = 0.2;

/// What one run measures besides the plans.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Extras {
    /// Print where the instructions went, by function.
    pub profile: bool,
    /// Steer one closed-loop insertion per scenario (the per-reading figures), and one more of
    /// each scenario that keeps no reserve, planned with one as for a steered insertion
    /// (`NAME-steered`).
    pub steering: bool,
}

/// Measures one board: build, sizes, then one QEMU run planning every scenario (and steering
/// it, unless `extras` leaves that out). With a profile, also prints where the instructions went,
/// by function: the plans' alone when steering is left out.
pub fn measure(
    root: &Path,
    board: &Board,
    plugin: &Path,
    scenarios: &[NamedScenario],
    extras: Extras,
) -> Result<BoardFigures> {
    let profile = extras.profile;
    let image = artifacts::build_firmware(root, board.name, board.features)?;
    let footprint = elf::footprint(&image)?;
    let dir = root
        .join("firmware")
        .join("target")
        .join("device-bench")
        .join(board.name);
    let mut qemu = qemu::Qemu::start(board.machine, &image, plugin, &dir, profile)?;
    // Ids from 1, as every run: an id's length on the wire changes the device's count.
    let mut device = Client::new(needle_link::tcp(qemu.connect()?)?, LINK)
        .with_first_id(1)
        .with_quiet_planning(PLAN_SILENCE);
    device
        .hello_within(Duration::from_secs(20), Duration::from_millis(300))
        .with_context(|| format!("{} in QEMU {}", board.name, board.machine))?;
    let mut instructions = Vec::new();
    let mut matches_host = Vec::new();
    for s in scenarios {
        let host = encoded(&planner_core::device::plan_as_device(&s.scenario, s.chance))?;
        let before = qemu.counts()?.len();
        let on_device = device
            .plan_bounded(&s.scenario, s.chance, &mut |_| {})
            .with_context(|| format!("planning {} on {}", s.name, board.name))?;
        let counts = qemu.counts()?;
        if counts.len() != before + 1 {
            bail!(
                "{}: expected one instruction count for {}, the plugin gave {}",
                board.name,
                s.name,
                counts.len().saturating_sub(before)
            );
        }
        instructions.push((s.name.clone(), counts[before]));
        matches_host.push((s.name.clone(), encoded(&on_device)? == host));
    }
    let mut replan_instructions = Vec::new();
    for s in scenarios.iter().filter(|_| extras.steering) {
        let mut steer = |name: String, scenario: &Scenario, how: &Steered| -> Result<()> {
            let r = crate::replan_bench::measure(&mut device, &qemu, scenario, how)
                .with_context(|| format!("steering {name} on {}", board.name))?;
            replan_instructions.push((name, r));
            Ok(())
        };
        steer(s.name.clone(), &s.scenario, &Steered::DEFAULT)?;
        // The same scenario planned for a steered insertion: its arcs keep curvature in hand, and
        // its replans try more forms before they give up (the costliest readings: docs/firmware.md).
        let mut steered = s.scenario.clone();
        if steered.options.curvature_reserve == 0.0 {
            steered.options.curvature_reserve = STEERED_RESERVE;
            steer(format!("{}-steered", s.name), &steered, &Steered::DEFAULT)?;
        }
        // A scenario planned under a collision bound is one a lab steers: steered again as a lab
        // sets it up (its reserve and steering), in the clinical world, where the replans try
        // the most turns.
        if s.chance.is_some() {
            let mut lab = s.scenario.clone();
            lab.options.curvature_reserve = crate::replan_bench::LAB_RESERVE;
            steer(format!("{}-lab", s.name), &lab, &Steered::LAB)?;
        }
    }
    // Last: the stage's steps, each counted alone, after every plan and reading.
    let steps = if board.moves_in_qemu {
        crate::step_bench::measure(&mut device, &qemu)
            .with_context(|| format!("the step interrupt on {}", board.name))?
    } else {
        None
    };
    drop(device);
    let len = footprint
        .stack_top
        .checked_sub(footprint.stack_bottom)
        .context("the image's stack ends above its start (_stack_end > _stack_start)")?;
    let memory = qemu.read_memory_and_quit(footprint.stack_bottom, len)?;
    if profile {
        let text = profile::report(&image, &dir.join("profile.txt"), 30)?;
        eprintln!("{}: {text}", board.name);
    }
    Ok(BoardFigures {
        board: board.name.to_owned(),
        flash_bytes: footprint.flash_bytes,
        static_ram_bytes: footprint.static_ram_bytes,
        peak_stack_bytes: elf::peak_stack(&memory, STACK_PAINT),
        instructions,
        matches_host,
        replan_instructions,
        steps,
    })
}

/// Builds the plugin, then measures every board.
pub fn measure_all(
    root: &Path,
    scenarios: &[NamedScenario],
    extras: Extras,
) -> Result<Vec<BoardFigures>> {
    ensure_target()?;
    ensure_qemu()?;
    let plugin = artifacts::build_plugin(root)?;
    BOARDS
        .iter()
        .map(|b| measure(root, b, &plugin, scenarios, extras))
        .collect()
}

/// `cargo xtask device-bench` options.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario files (default: examples/paper.toml, devtools/workloads/space.toml — the
    /// 3-D example planned unbounded —, examples/paper-bounded.toml and spheres256.toml); a
    /// file's collision bound is planned under on the device too.
    files: Vec<PathBuf>,
    /// Print one JSON object per board (keys `board`, `flash_bytes`, `static_ram_bytes`,
    /// `peak_stack_bytes`, `instructions`, `matches_host`, `replan_instructions`,
    /// `step_instructions`: `null` on a board without axes), as a JSON array.
    #[arg(long)]
    json: bool,
    /// Fail when a board leaves any device budget (`--budgets` lists them), or a device plan
    /// differs from the host's.
    #[arg(long)]
    check: bool,
    /// Print the device budgets as a Markdown table and measure nothing.
    #[arg(long)]
    budgets: bool,
    /// Also print, per board, the functions the measured instructions were spent in (slower).
    #[arg(long)]
    profile: bool,
    /// Measure the plans only, not the closed-loop steering (faster; with `--profile`, a profile
    /// of the plans alone). `replan_instructions` is then empty, so `--check` is refused with it.
    #[arg(long, conflicts_with = "check")]
    plan_only: bool,
    /// The needle-planner checkout holding firmware/ and tools/ (default: the one this was
    /// built from).
    #[arg(long)]
    root: Option<PathBuf>,
}

/// Runs `cargo xtask device-bench`, reading scenario files with `load`.
pub fn run(args: &Args, load: LoadScenario) -> Result<()> {
    if args.budgets {
        write!(std::io::stdout(), "{}", budgets::markdown_table())?;
        return Ok(());
    }
    let root = match &args.root {
        Some(r) => r.clone(),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join(".."),
    };
    if !root.join("firmware").join("Cargo.toml").is_file() {
        bail!(
            "{} holds no firmware/ (pass --root CHECKOUT)",
            root.display()
        );
    }
    let files = if args.files.is_empty() {
        vec![
            root.join("examples/paper.toml"),
            root.join("devtools/workloads/space.toml"),
            root.join("examples/paper-bounded.toml"),
            root.join("examples/spheres256.toml"),
        ]
    } else {
        args.files.clone()
    };
    let scenarios = load_scenarios(&files, load)?;
    let extras = Extras {
        profile: args.profile,
        steering: !args.plan_only,
    };
    let figures = measure_all(&root, &scenarios, extras)?;
    if args.json {
        let all: Vec<Value> = figures.iter().map(BoardFigures::to_json).collect();
        writeln!(std::io::stdout(), "{}", serde_json::to_string_pretty(&all)?)?;
    } else {
        write!(std::io::stdout(), "{}", table(&figures))?;
    }
    for o in verdict(&figures, args.check)? {
        eprintln!("warning: {o}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    #[test]
    fn plan_only_cannot_be_checked_against_the_steering_budget() {
        assert!(Cli::try_parse_from(["device-bench", "--plan-only", "--check"]).is_err());
        let cli = Cli::try_parse_from(["device-bench", "--plan-only", "--profile"]).unwrap();
        assert!(cli.args.plan_only && cli.args.profile && !cli.args.check);
    }

    #[test]
    fn budgets_are_printed_without_measuring() {
        let cli =
            Cli::try_parse_from(["device-bench", "--budgets", "--root", "/nonexistent"]).unwrap();
        // Measuring would refuse a root without firmware/; printing the budgets needs none.
        assert!(run(&cli.args, &|_| unreachable!("no scenario is read")).is_ok());
    }
}
