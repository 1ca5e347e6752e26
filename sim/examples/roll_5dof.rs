//! The roll estimate with a 5-DOF sensor, measured: 100 closed-loop runs of the paper's scenario
//! (`examples/paper.toml`, as `Scenario::paper`) with `tracker_dof = 5` and everything else
//! default (as `needle simulate examples/paper.toml --closed-loop --perturb tracker_dof=5`: seeds
//! 1 to 100), and the same with a 6-DOF sensor. Prints the roll error's RMS over every reading
//! of every run (readings while the shaft spins left out: the roll means nothing then) and each
//! run's median and largest error; writes one run's errors against insertion depth, 5-DOF and
//! 6-DOF on one plot, as SVG.
//!
//! `cargo run --release -p needle-sim --example roll_5dof [-- RUNS [SVG]]`
//! (default 100 runs, docs/figures/roll-5dof.svg). Every figure is simulated.

use needle_sim::{
    roll_trace, Conditions, Perturbation, Planned, RollSample, RollSummary, TrackerFaults,
    WorldEffects,
};
use planner_core::execute::schedule::{schedule, Schedule};
use planner_core::steer::SteerConfig;
use planner_core::{plan, Scenario};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The run drawn: the first seed, as `needle simulate`'s first run.
const DRAWN_SEED: u64 = 1;

type Failure = Box<dyn std::error::Error>;

struct Campaign {
    scenario: Scenario,
    planned: Planned,
    schedule: Schedule,
}

impl Campaign {
    fn new() -> Result<Campaign, Failure> {
        let scenario = Scenario::paper();
        let report = plan(&scenario)?;
        let best = report
            .best()
            .ok_or("the paper's scenario has no path")?
            .clone();
        let schedule = schedule(&scenario, &best).map_err(|e| format!("cannot schedule: {e:?}"))?;
        let planned = Planned::of(&scenario, &best);
        Ok(Campaign {
            scenario,
            planned,
            schedule,
        })
    }

    /// The roll errors of the run of `seed` with a sensor of `dof` degrees of freedom, and its
    /// target error (mm).
    fn run(&self, dof: u8, seed: u64) -> Result<(Vec<RollSample>, f32), Failure> {
        let mut effects = WorldEffects::default();
        effects.set("tracker_dof", f32::from(dof))?;
        let (p, f) = (Perturbation::default(), TrackerFaults::default());
        let world = Conditions {
            perturbation: &p,
            effects: &effects,
            faults: &f,
        };
        let config = SteerConfig::DEFAULT;
        let (s, planned, sched) = (&self.scenario, &self.planned, &self.schedule);
        let (run, samples) = roll_trace(s, planned, sched, &world, &config, seed)?;
        Ok((samples, run.run.target_error))
    }
}

/// Runs `runs` seeds with a sensor of `dof`, printing each run's figures; returns every sample.
fn campaign(c: &Campaign, dof: u8, runs: u64) -> Result<Vec<RollSample>, Failure> {
    println!("{dof}-DOF: seed, readings counted, RMS, median |error|, max |error| (degrees), target error (mm)");
    let (mut all, mut before, mut after) = (Vec::new(), Vec::new(), Vec::new());
    let (mut medians, mut target_errors) = (Vec::new(), Vec::new());
    for seed in 1..=runs {
        let (samples, target_error) = c.run(dof, seed)?;
        let s = RollSummary::of(&samples);
        let first_spin = samples.iter().position(|s| s.spinning);
        let (b, a) = samples.split_at(first_spin.unwrap_or(samples.len()));
        before.extend_from_slice(b);
        after.extend_from_slice(a);
        println!(
            "  {seed:3} {:4} {:7.2} {:7.2} {:7.2}   {target_error:.3}",
            s.samples, s.rms_deg, s.median_abs_deg, s.max_abs_deg
        );
        medians.push(s.median_abs_deg);
        target_errors.push(target_error);
        all.extend(samples);
    }
    let s = RollSummary::of(&all);
    medians.sort_by(f32::total_cmp);
    let mean_target = target_errors.iter().sum::<f32>() / target_errors.len().max(1) as f32;
    println!(
        "{dof}-DOF over {runs} runs: RMS {:.2} degrees over {} readings ({} spinning left out); \
         median |error| {:.2}, max {:.2}; median of the runs' medians {:.2}; mean target error \
         {mean_target:.3} mm",
        s.rms_deg,
        s.samples,
        all.len() - s.samples,
        s.median_abs_deg,
        s.max_abs_deg,
        medians.get(medians.len() / 2).copied().unwrap_or(0.0),
    );
    let (b, a) = (RollSummary::of(&before), RollSummary::of(&after));
    println!(
        "  before the first spun line: RMS {:.2} over {} readings, max {:.2}; from it on: RMS {:.2} over {}, max {:.2}",
        b.rms_deg, b.samples, b.max_abs_deg, a.rms_deg, a.samples, a.max_abs_deg
    );
    Ok(all)
}

fn main() -> Result<(), Failure> {
    let mut args = std::env::args().skip(1);
    let runs: u64 = match args.next() {
        Some(a) => a.parse()?,
        None => 100,
    };
    let svg = args.next().map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/figures/roll-5dof.svg")
    });
    let c = Campaign::new()?;
    campaign(&c, 5, runs)?;
    campaign(&c, 6, runs)?;
    let (five, _) = c.run(5, DRAWN_SEED)?;
    let (six, _) = c.run(6, DRAWN_SEED)?;
    std::fs::write(&svg, plot(&five, &six))?;
    println!("wrote {}", svg.display());
    Ok(())
}

/// The plot's frame: the drawing area inside the margins and the data ranges it maps.
struct Axes {
    x0: f32,
    x1: f32,
    y0: f32,
    y1: f32,
    depth: f32,
    error: f32,
}

impl Axes {
    fn x(&self, depth_mm: f32) -> f32 {
        self.x0 + (self.x1 - self.x0) * depth_mm / self.depth
    }
    fn y(&self, error_deg: f32) -> f32 {
        let e = error_deg.clamp(-self.error, self.error);
        self.y0 + (self.y1 - self.y0) * (self.error - e) / (2.0 * self.error)
    }
}

/// The polylines of the non-spinning stretches of `samples`.
fn polylines(out: &mut String, a: &Axes, samples: &[RollSample], colour: &str) {
    let mut points = Vec::new();
    let mut flush = |points: &mut Vec<String>| {
        if let [alone] = points.as_slice() {
            // A reading between two spins: a dot, not a line.
            let (x, y) = alone.split_once(',').unwrap_or(("0", "0"));
            let _ = writeln!(out, r#"<circle cx="{x}" cy="{y}" r="2" fill="{colour}"/>"#);
        } else if points.len() > 1 {
            let _ = writeln!(
                out,
                r#"<polyline fill="none" stroke="{colour}" stroke-width="1.5" points="{}"/>"#,
                points.join(" ")
            );
        }
        points.clear();
    };
    for s in samples {
        if s.spinning {
            flush(&mut points);
        } else {
            points.push(format!("{:.1},{:.1}", a.x(s.depth_mm), a.y(s.error_deg)));
        }
    }
    flush(&mut points);
}

/// Shades the depths over which `samples` were taken with the shaft spinning.
fn shade_spinning(out: &mut String, a: &Axes, samples: &[RollSample]) {
    let mut start: Option<f32> = None;
    let mut last = 0.0;
    for s in samples {
        match (s.spinning, start) {
            (true, None) => start = Some(last),
            (false, Some(from)) => {
                let (x, w) = (a.x(from), a.x(s.depth_mm) - a.x(from));
                let h = a.y1 - a.y0;
                let _ = writeln!(
                    out,
                    r##"<rect x="{x:.1}" y="{:.1}" width="{w:.1}" height="{h:.1}" fill="#dddddd"/>"##,
                    a.y0
                );
                start = None;
            }
            _ => {}
        }
        last = s.depth_mm;
    }
}

/// The step between the error axis's ticks for errors up to `largest` degrees.
fn tick(largest: f32) -> f32 {
    if largest > 40.0 {
        20.0
    } else {
        10.0
    }
}

/// Axes, ticks and labels.
fn frame(out: &mut String, a: &Axes) {
    let step = tick(a.error);
    let mut e = -a.error;
    while e <= a.error + 1e-3 {
        let y = a.y(e);
        let stroke = if e == 0.0 { "#888888" } else { "#eeeeee" };
        let _ = writeln!(
            out,
            r#"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{stroke}"/><text x="{:.1}" y="{:.1}" text-anchor="end" font-size="12">{e:.0}</text>"#,
            a.x0,
            a.x1,
            a.x0 - 6.0,
            y + 4.0
        );
        e += step;
    }
    let mut d = 0.0;
    while d <= a.depth + 1e-3 {
        let x = a.x(d);
        let _ = writeln!(
            out,
            r#"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="black"/><text x="{x:.1}" y="{:.1}" text-anchor="middle" font-size="12">{d:.0}</text>"#,
            a.y1,
            a.y1 + 5.0,
            a.y1 + 19.0
        );
        d += 10.0;
    }
    let _ = writeln!(
        out,
        r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="black"/>"#,
        a.x0,
        a.y0,
        a.x1 - a.x0,
        a.y1 - a.y0
    );
    let _ = writeln!(
        out,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="13">insertion depth (mm, commanded)</text>"#,
        (a.x0 + a.x1) / 2.0,
        a.y1 + 38.0
    );
    let _ = writeln!(
        out,
        r#"<text transform="translate(18,{:.1}) rotate(-90)" text-anchor="middle" font-size="13">roll error (degrees)</text>"#,
        (a.y0 + a.y1) / 2.0
    );
}

/// The SVG: the 5-DOF and 6-DOF runs' roll errors against insertion depth.
fn plot(five: &[RollSample], six: &[RollSample]) -> String {
    let counted = five.iter().chain(six).filter(|s| !s.spinning);
    let largest = counted.map(|s| s.error_deg.abs()).fold(0.0f32, f32::max);
    let depth = five
        .iter()
        .chain(six)
        .map(|s| s.depth_mm)
        .fold(0.0f32, f32::max);
    let a = Axes {
        x0: 60.0,
        x1: 760.0,
        y0: 50.0,
        y1: 370.0,
        depth: (depth / 10.0).ceil().max(1.0) * 10.0,
        error: (largest / tick(largest)).ceil().max(1.0) * tick(largest),
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="800" height="430" viewBox="0 0 800 430" font-family="sans-serif">"#
    );
    let _ = writeln!(out, r#"<rect width="800" height="430" fill="white"/>"#);
    let _ = writeln!(
        out,
        r#"<text x="400" y="22" text-anchor="middle" font-size="14">Roll estimate error along one closed-loop insertion (paper.toml, seed {DRAWN_SEED}; simulated)</text>"#
    );
    shade_spinning(&mut out, &a, five);
    frame(&mut out, &a);
    polylines(&mut out, &a, five, "#d62728");
    polylines(&mut out, &a, six, "#1f77b4");
    let legend = [
        ("#d62728", "5-DOF sensor (no roll measured)"),
        ("#1f77b4", "6-DOF sensor"),
    ];
    let _ = writeln!(
        out,
        r##"<rect x="70" y="300" width="330" height="62" fill="white" stroke="#aaaaaa"/>"##
    );
    for (i, (colour, label)) in legend.iter().enumerate() {
        let y = 314.0 + 18.0 * i as f32;
        let _ = writeln!(
            out,
            r#"<line x1="78" y1="{y}" x2="103" y2="{y}" stroke="{colour}" stroke-width="2"/><text x="110" y="{:.0}" font-size="12">{label}</text>"#,
            y + 4.0
        );
    }
    let _ = writeln!(
        out,
        r##"<rect x="78" y="345" width="25" height="10" fill="#dddddd"/><text x="110" y="354" font-size="12">shaft spinning (5-DOF run; gaps in both lines)</text>"##
    );
    out.push_str("</svg>\n");
    out
}
