//! What `needle simulate` is asked: the scenario file, the runs, the world, the controller's
//! settings, the device and the output (the `needle` binary reads these from its flags and
//! refuses the ones that mean nothing alone).

use needle_device::LinkOptions;
use std::path::PathBuf;

/// `needle simulate`
#[derive(Clone, Debug)]
pub struct SimulateOptions {
    /// Scenario file (TOML, see examples/paper.toml).
    pub file: PathBuf,
    /// Simulated insertions, 1 to [`MAX_RUNS`] (checked with the scenario).
    pub runs: usize,
    /// Seed of the first run (run i uses seed + i).
    pub seed: u64,
    /// Plan and simulate only this form (e.g. RL) instead of the best.
    pub form: Option<String>,
    /// Changes to the world's perturbation or effects, `KEY=VALUE`, over `world`.
    pub perturb: Vec<String>,
    /// The named world the runs are made in (`default`, `clinical`).
    pub world: Option<String>,
    /// Print one JSON object instead of the table.
    pub json: bool,
    /// With `json`: every run's draws, figures, points and steps.
    pub detail: bool,
    /// Also draw the plan and the executed paths (SVG; the file is opened before simulating).
    pub plot: Option<PathBuf>,
    /// Also write files 3D Slicer opens into this folder: the plan and every simulated path.
    pub export: Option<PathBuf>,
    /// Threads, at least 1 (`None`: every core).
    pub threads: Option<usize>,
    /// Steer every run with the closed-loop controller instead of executing the schedule open
    /// loop.
    pub closed_loop: bool,
    /// Tracker faults, `KEY=VALUE` (closed loop).
    pub faults: Vec<String>,
    /// What the controller is told over the file's `[steering]`, `KEY=VALUE` (closed loop).
    pub steer: Vec<String>,
    /// Steer on this device instead of in-process (closed loop).
    pub link: Option<LinkOptions>,
    /// With `closed_loop`: also run the same worlds open loop and print both side by side.
    pub compare_open_loop: bool,
}

impl Default for SimulateOptions {
    /// The command's defaults, for no file yet.
    fn default() -> Self {
        SimulateOptions {
            file: PathBuf::new(),
            runs: 100,
            seed: 1,
            form: None,
            perturb: Vec::new(),
            world: None,
            json: false,
            detail: false,
            plot: None,
            export: None,
            threads: None,
            closed_loop: false,
            faults: Vec::new(),
            steer: Vec::new(),
            link: None,
            compare_open_loop: false,
        }
    }
}

/// The most runs one simulation makes: each keeps a few numbers for the table, so a larger count
/// is a typing slip that would otherwise end in an allocation abort, not in an answer.
pub const MAX_RUNS: usize = 1_000_000;

/// The most scenarios one benchmark generates.
pub const MAX_SCENARIOS: usize = 100_000;
