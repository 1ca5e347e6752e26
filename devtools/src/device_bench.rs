//! `needle device-bench`: what the planner costs on the microcontroller, measured in QEMU.
//!
//! For each board it builds the release firmware, reads flash and static RAM from the image,
//! boots it in QEMU (mps2-an386 for the `mps2-an386` build, netduinoplus2 for the `stm32f4`
//! build) with the instruction-count plugin (`tools/insn-count`), plans each scenario over the
//! emulated UART, and reads the stack's high-water mark from the painted stack at the end. Each
//! device plan is also checked against the host's plan, bit for bit.

use crate::firmware_artifacts::{self as artifacts, ensure_qemu, ensure_target};
use crate::{budgets, elf, profile, qemu};
use anyhow::{bail, Context, Result};
use needle_link::{Client, ClientConfig};
use planner_core::wire::PlanResult;
use planner_core::Scenario;
use serde_json::{json, Map, Value};
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
}

/// The boards measured.
pub const BOARDS: [Board; 2] = [
    Board {
        name: "mps2-an386",
        features: "mps2-an386",
        machine: "mps2-an386",
    },
    Board {
        name: "stm32f4",
        features: "stm32f4",
        machine: "netduinoplus2",
    },
];

/// Figures of one board.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BoardFigures {
    /// Board name.
    pub board: String,
    /// See [`elf::Footprint`].
    pub flash_bytes: u64,
    /// See [`elf::Footprint`].
    pub static_ram_bytes: u64,
    /// Deepest stack use over all the runs (bytes).
    pub peak_stack_bytes: u64,
    /// Scenario name and instructions executed for its plan.
    pub instructions: Vec<(String, u64)>,
    /// Scenario name and whether the device's plan equals the host's bit for bit.
    pub matches_host: Vec<(String, bool)>,
    /// Scenario name and the instructions per steering reading of one closed-loop insertion.
    pub replan_instructions: Vec<(String, crate::replan_bench::ReplanFigures)>,
}

impl BoardFigures {
    /// The JSON object of `needle device-bench --json`.
    pub fn to_json(&self) -> Value {
        let map = |v: &[(String, u64)]| {
            v.iter()
                .map(|(k, n)| (k.clone(), json!(n)))
                .collect::<Map<_, _>>()
        };
        let same = self
            .matches_host
            .iter()
            .map(|(k, b)| (k.clone(), json!(b)))
            .collect::<Map<_, _>>();
        json!({
            "board": self.board,
            "flash_bytes": self.flash_bytes,
            "static_ram_bytes": self.static_ram_bytes,
            "peak_stack_bytes": self.peak_stack_bytes,
            "instructions": map(&self.instructions),
            "matches_host": same,
            "replan_instructions": self
                .replan_instructions
                .iter()
                .map(|(k, r)| {
                    let v = json!({
                        "max": r.max,
                        "median": r.median,
                        "readings": r.readings,
                        "replans": r.replans,
                    });
                    (k.clone(), v)
                })
                .collect::<Map<_, _>>(),
        })
    }

    /// Reads back one object of `needle device-bench --json` (what [`Self::to_json`] wrote).
    pub fn from_json(v: &Value) -> Result<BoardFigures> {
        let number = |v: &Value, key: &str| {
            v[key]
                .as_u64()
                .with_context(|| format!("device-bench JSON: {key} is not a count"))
        };
        let object = |key: &str| {
            v[key]
                .as_object()
                .with_context(|| format!("device-bench JSON: {key} is not an object"))
        };
        let counts = object("instructions")?
            .iter()
            .map(|(k, n)| {
                let n = n.as_u64().with_context(|| {
                    format!("device-bench JSON: instructions.{k} is not a count")
                })?;
                Ok((k.clone(), n))
            })
            .collect::<Result<_>>()?;
        let matches_host = object("matches_host")?
            .iter()
            .map(|(k, b)| {
                let same = b.as_bool().context("device-bench JSON: matches_host")?;
                Ok((k.clone(), same))
            })
            .collect::<Result<_>>()?;
        let replan_instructions = object("replan_instructions")?
            .iter()
            .map(|(k, r)| {
                let figures = crate::replan_bench::ReplanFigures {
                    readings: usize::try_from(number(r, "readings")?)?,
                    replans: u32::try_from(number(r, "replans")?)?,
                    max: number(r, "max")?,
                    median: number(r, "median")?,
                };
                Ok((k.clone(), figures))
            })
            .collect::<Result<_>>()?;
        Ok(BoardFigures {
            board: v["board"]
                .as_str()
                .context("device-bench JSON: board is not a name")?
                .to_owned(),
            flash_bytes: number(v, "flash_bytes")?,
            static_ram_bytes: number(v, "static_ram_bytes")?,
            peak_stack_bytes: number(v, "peak_stack_bytes")?,
            instructions: counts,
            matches_host,
            replan_instructions,
        })
    }

    /// What `--check` refuses, as sentences: every budget of [`budgets::BUDGETS`] left (or not
    /// measured), and every device plan that differs from the host's. Empty when all is well.
    pub fn problems(&self) -> Vec<String> {
        let mut out: Vec<String> = budgets::breaches(self)
            .iter()
            .map(ToString::to_string)
            .collect();
        for (name, same) in &self.matches_host {
            if !same {
                out.push(format!(
                    "{}: the device's plan of {name} differs from the host's",
                    self.board
                ));
            }
        }
        out
    }
}

/// A scenario to plan: its name (file stem) and contents.
pub struct NamedScenario {
    /// File stem, the key in `instructions`.
    pub name: String,
    /// The scenario.
    pub scenario: Scenario,
}

/// Reads a scenario file (`needle`'s TOML reader; passed in, since this crate sits below
/// `needle-cli`).
pub type LoadScenario<'a> = &'a dyn Fn(&Path) -> Result<Scenario>;

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
            let scenario = load(f)?;
            Ok(NamedScenario { name, scenario })
        })
        .collect()
}

fn encoded(result: &PlanResult) -> Result<Vec<u8>> {
    let mut buf = vec![0u8; planner_core::wire::MAX_PLAN_RESULT];
    Ok(postcard::to_slice(result, &mut buf)
        .context("encoding a plan")?
        .to_vec())
}

/// What one run measures besides the plans.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Extras {
    /// Print where the instructions went, by function.
    pub profile: bool,
    /// Steer one closed-loop insertion per scenario (the per-reading figures).
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
        let host = encoded(&planner_core::plan_scheduled(&s.scenario))?;
        let before = qemu.counts()?.len();
        let on_device = device
            .plan(&s.scenario, &mut |_| {})
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
        let r = crate::replan_bench::measure(&mut device, &qemu, &s.scenario)
            .with_context(|| format!("steering {} on {}", s.name, board.name))?;
        replan_instructions.push((s.name.clone(), r));
    }
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

/// The human-readable report.
pub fn table(figures: &[BoardFigures]) -> String {
    let mut s = String::new();
    for f in figures {
        s.push_str(&format!(
            "{}: flash {} B ({:.1} KiB), static RAM {} B, peak stack {} B, RAM total {:.1} KiB\n",
            f.board,
            f.flash_bytes,
            f.flash_bytes as f64 / 1024.0,
            f.static_ram_bytes,
            f.peak_stack_bytes,
            (f.static_ram_bytes + f.peak_stack_bytes) as f64 / 1024.0
        ));
        for ((name, n), (_, same)) in f.instructions.iter().zip(&f.matches_host) {
            s.push_str(&format!(
                "  {name}: {n} instructions per plan ({:.2} M), plan {} the host's\n",
                *n as f64 / 1e6,
                if *same { "equals" } else { "DIFFERS from" }
            ));
        }
        if f.replan_instructions.is_empty() {
            s.push_str("  steering not measured (--plan-only)\n");
        }
        for (name, r) in &f.replan_instructions {
            s.push_str(&format!(
                "  {name} steered: {} readings, {} replans; per reading max {} (≈ {:.1} ms at \
                 168 MHz), median {} instructions (≈ {:.0} readings/s at 168 MHz, one \
                 instruction per cycle)\n",
                r.readings,
                r.replans,
                r.max,
                r.max as f64 / 168e3,
                r.median,
                168e6 / r.median.max(1) as f64
            ));
        }
    }
    s
}

/// `needle device-bench` options.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario files (default: examples/paper.toml and examples/space.toml).
    files: Vec<PathBuf>,
    /// Print one JSON object per board (keys `board`, `flash_bytes`, `static_ram_bytes`,
    /// `peak_stack_bytes`, `instructions`, `matches_host`, `replan_instructions`), as a JSON
    /// array.
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
    /// The needle-planner checkout holding firmware/ and tools/ (default: where `needle` was built).
    #[arg(long)]
    root: Option<PathBuf>,
}

/// Runs `needle device-bench`, reading scenario files with `load`.
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
            root.join("examples/space.toml"),
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
    let over: Vec<String> = figures.iter().flat_map(BoardFigures::problems).collect();
    if args.check && !over.is_empty() {
        bail!("{} check(s) failed:\n  {}", over.len(), over.join("\n  "));
    }
    for o in &over {
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

    #[test]
    fn the_json_reads_back_as_the_figures_it_was_written_from() {
        let figures = BoardFigures {
            board: "stm32f4".into(),
            flash_bytes: 127_496,
            static_ram_bytes: 11_032,
            peak_stack_bytes: 20_168,
            instructions: vec![("paper".into(), 13_704_413), ("space".into(), 82_944_334)],
            matches_host: vec![("paper".into(), true), ("space".into(), false)],
            replan_instructions: vec![(
                "paper".into(),
                crate::replan_bench::ReplanFigures {
                    readings: 537,
                    replans: 410,
                    max: 408_953,
                    median: 261_697,
                },
            )],
        };
        let back = BoardFigures::from_json(&figures.to_json()).unwrap();
        assert_eq!(back, figures);
        // Within every budget, but the device's space plan differs from the host's.
        assert_eq!(
            back.problems(),
            ["stm32f4: the device's plan of space differs from the host's"]
        );
        let mut broken = figures.to_json();
        broken["flash_bytes"] = json!("many");
        let error = BoardFigures::from_json(&broken).unwrap_err().to_string();
        assert!(error.contains("flash_bytes"), "{error}");
    }

    #[test]
    fn the_table_says_when_steering_was_not_measured() {
        let figures = BoardFigures {
            board: "mps2-an386".into(),
            flash_bytes: 1,
            static_ram_bytes: 2,
            peak_stack_bytes: 3,
            instructions: vec![("paper".into(), 14_000_000)],
            matches_host: vec![("paper".into(), true)],
            replan_instructions: Vec::new(),
        };
        let text = table(&[figures]);
        assert!(
            text.contains("paper: 14000000 instructions per plan"),
            "{text}"
        );
        assert!(text.contains("steering not measured"), "{text}");
    }
}
