//! Where the closed loop's target error comes from, on the runs that reached: at the last
//! reading, the estimated target against the true one (where the tissue has carried it) and the
//! estimated tip against the true one, each split along the tip's heading and across it, beside
//! the true tip's own error. The runs are those `needle simulate FILE --closed-loop --runs RUNS
//! --seed 1 FLAGS...` makes (the same plan, seeds and controller).
//!
//! `cargo run --release -p needle-cli --example end_error -- FILE RUNS [FLAGS...]` (the flags of
//! `needle simulate` that make the world and tell the controller: `--world`, `--perturb`,
//! `--fault`, `--steer`, `--form`; e.g. `--world clinical`). Means in mm. Every figure is
//! simulated.

use clap::Parser;
use needle_sim::{closed_loop_observed, in_process};
use needle_simulate::request::Request;
use needle_simulate::{closed_loop_setup, run_seed};
use planner_core::model::kinematics::V3;

type Failure = Box<dyn std::error::Error>;

/// What the last reading of one run showed: estimated and true target, estimated and true tip,
/// the true heading.
type Last = (V3, V3, V3, V3, V3);

/// Sums of |along| and |across| of the target estimate's, the tip estimate's and the true
/// tip's error, and of the true target error.
#[derive(Default)]
struct Tally {
    sums: [f64; 7],
    runs: usize,
}

impl Tally {
    fn add(&mut self, (est_target, target, est_tip, tip, heading): Last, error: f32) {
        let split = |v: V3| {
            let along = v.dot(&heading);
            (along.abs(), (v - heading * along).norm())
        };
        let (ta, tx) = split(est_target - target);
        let (pa, px) = split(est_tip - tip);
        let (fa, fx) = split(tip - target);
        for (sum, v) in self.sums.iter_mut().zip([ta, tx, pa, px, fa, fx, error]) {
            *sum += f64::from(v);
        }
        self.runs += 1;
    }

    fn print(&self) {
        let m: Vec<String> = self
            .sums
            .iter()
            .map(|s| format!("{:.3}", s / self.runs.max(1) as f64))
            .collect();
        println!("runs reached: {}", self.runs);
        println!("target estimate off: along {} across {}", m[0], m[1]);
        println!("tip estimate off:    along {} across {}", m[2], m[3]);
        println!("true tip off target: along {} across {}", m[4], m[5]);
        println!("target error (mean): {}", m[6]);
    }
}

/// The scenario, the run count, and the flags of `needle simulate` the runs are made with.
#[derive(Parser)]
struct Args {
    file: std::path::PathBuf,
    runs: usize,
    #[arg(long)]
    form: Option<String>,
    #[arg(long)]
    perturb: Vec<String>,
    #[arg(long)]
    world: Option<String>,
    #[arg(long)]
    fault: Vec<String>,
    #[arg(long)]
    steer: Vec<String>,
}

fn main() -> Result<(), Failure> {
    let args = Args::parse();
    let asked = Request {
        form: args.form,
        perturb: args.perturb,
        world: args.world,
        faults: args.fault,
        steer: args.steer,
        ..Request::default()
    };
    let runs = args.runs;
    let setup = closed_loop_setup(&args.file, 1, &asked)?;
    let world = setup.conditions();
    let mut tally = Tally::default();
    for i in 0..runs {
        let seed = run_seed(setup.seed, i);
        let mut ctl = in_process(&setup.scenario, &setup.prepared.schedule, &setup.config)
            .map_err(|e| format!("seed {seed}: {e:?}"))?;
        let mut last: Option<Last> = None;
        let run = closed_loop_observed(
            &setup.scenario,
            &setup.planned,
            &setup.prepared.schedule,
            &world,
            &mut ctl,
            seed,
            |s| {
                let e = s.controller.estimate();
                last = Some((e.target, s.target, e.tip.p, s.tip.p, s.tip.e3()));
            },
        )
        .map_err(|e| format!("seed {seed}: {e:?}"))?;
        if let (None, Some(last)) = (run.stop_reason, last) {
            tally.add(last, run.run.target_error);
        }
    }
    tally.print();
    Ok(())
}
