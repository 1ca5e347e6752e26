//! The roll estimate with a 5-DOF sensor on scenario files (a generated family): each file's
//! closed-loop runs as `needle simulate FILE --closed-loop --runs RUNS --seed 1 --perturb
//! tracker_dof=DOF` makes them (the same plan, seeds and controller), with the roll error at
//! every reading (`needle_sim::roll_trace`; readings while the shaft spins left out). Prints,
//! for 5-DOF and 6-DOF: the roll error's RMS over all readings, before the first spun line and
//! from it on; the target error's mean and 95th percentile; the runs reached and collided.
//!
//! `cargo run --release -p needle-cli --example roll_family -- DIR [RUNS]` (every `*.toml` in DIR,
//! default 25 runs each). Every figure is simulated.

use needle_sim::{roll_trace, RollSample, RollSummary};
use needle_simulate::request::Request;
use needle_simulate::{closed_loop_setup, run_seed, Spread};

type Failure = Box<dyn std::error::Error>;

/// What the runs of one sensor left.
#[derive(Default)]
struct Tally {
    before: Vec<RollSample>,
    after: Vec<RollSample>,
    target_errors: Vec<f32>,
    reached: usize,
    collisions: usize,
}

impl Tally {
    /// Runs `file` `runs` times from seed 1 with a sensor of `dof` degrees of freedom.
    fn add(&mut self, file: &std::path::Path, dof: u8, runs: usize) -> Result<(), Failure> {
        let asked = Request {
            perturb: vec![format!("tracker_dof={dof}")],
            ..Request::default()
        };
        let setup = closed_loop_setup(file, 1, &asked)?;
        let world = setup.conditions();
        let (s, planned, sched) = (&setup.scenario, &setup.planned, &setup.prepared.schedule);
        for i in 0..runs {
            let seed = run_seed(setup.seed, i);
            let (run, samples) = roll_trace(s, planned, sched, &world, &setup.config, seed)
                .map_err(|e| format!("{}: seed {seed}: {e}", file.display()))?;
            let first_spin = samples.iter().position(|s| s.spinning);
            let (b, a) = samples.split_at(first_spin.unwrap_or(samples.len()));
            self.before.extend_from_slice(b);
            self.after.extend_from_slice(a);
            self.target_errors.push(run.run.target_error);
            self.reached += usize::from(run.stop_reason.is_none());
            self.collisions += usize::from(run.run.collided);
        }
        Ok(())
    }

    fn print(&self, dof: u8) {
        let all: Vec<RollSample> = self.before.iter().chain(&self.after).copied().collect();
        let (s, b, a) = (
            RollSummary::of(&all),
            RollSummary::of(&self.before),
            RollSummary::of(&self.after),
        );
        let e = Spread::of(self.target_errors.iter().copied());
        let n = self.target_errors.len();
        println!(
            "{dof}-DOF, {n} runs: roll RMS {:.2} degrees over {} readings (before the first spun \
             line {:.2} over {}, from it on {:.2} over {}), median |error| {:.2}, max {:.2}; \
             target error mean {:.3} mm, p95 {:.3}; reached {:.1} %; collisions {}",
            s.rms_deg,
            s.samples,
            b.rms_deg,
            b.samples,
            a.rms_deg,
            a.samples,
            s.median_abs_deg,
            s.max_abs_deg,
            e.mean,
            e.p95,
            100.0 * self.reached as f64 / n.max(1) as f64,
            self.collisions
        );
    }
}

fn main() -> Result<(), Failure> {
    let mut args = std::env::args().skip(1);
    let dir = args.next().ok_or("usage: roll_family DIR [RUNS]")?;
    let runs: usize = match args.next() {
        Some(a) => a.parse()?,
        None => 25,
    };
    let mut files: Vec<_> = std::fs::read_dir(&dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    for dof in [5, 6] {
        let mut tally = Tally::default();
        for file in &files {
            tally.add(file, dof, runs)?;
        }
        tally.print(dof);
    }
    Ok(())
}
