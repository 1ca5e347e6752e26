//! The table `needle simulate` prints.

use super::steering::SteeringSummary;
use super::{Spread, Summary};
use needle_sim::{Perturbation, WorldEffects, KEYS, LAYER_DEPTHS_KEY, WORLD_KEYS};
use std::fmt::Write;

/// What the table's header names.
pub struct Header<'a> {
    /// Scenario file name.
    pub file: &'a str,
    /// The simulated form.
    pub form: &'a str,
    /// Number of runs.
    pub runs: usize,
    /// First seed.
    pub seed: u64,
}

impl Header<'_> {
    /// "simulated KIND insertions of FORM in FILE: N runs, seeds S..".
    fn title(&self, out: &mut String, kind: &str) {
        let _ = writeln!(
            out,
            "simulated {kind} insertions of {} in {}: {} runs, seeds {}..",
            self.form, self.file, self.runs, self.seed
        );
    }
}

/// The column heads after `what`, without the line's end (the open loop's may follow).
fn heads(out: &mut String, what: &str) {
    let _ = write!(
        out,
        "{what:<28}{:>9}{:>9}{:>9}{:>9}",
        "mean", "rms", "p95", "max"
    );
}

fn row(out: &mut String, what: &str, s: &Spread) {
    pair(out, what, s, None);
}

/// The perturbation every run drew from, `KEY=VALUE` for every key.
fn perturbation_line(out: &mut String, p: &Perturbation) {
    let values: Vec<String> = KEYS
        .iter()
        .map(|k| format!("{k}={}", p.get(k).unwrap_or(f32::NAN)))
        .collect();
    let _ = writeln!(out, "perturbation: {}", values.join(" "));
}

/// The world's effects, `KEY=VALUE` for every key, when any is on (the default world prints
/// no such line).
pub fn world_line(w: &WorldEffects) -> String {
    if w.is_off() {
        return String::new();
    }
    let values: Vec<String> = WORLD_KEYS
        .iter()
        .map(|k| format!("{k}={}", w.get(k).unwrap_or(f32::NAN)))
        .collect();
    let given = w
        .layer_depths_mm
        .map(|d| format!(" {LAYER_DEPTHS_KEY}={d}"))
        .unwrap_or_default();
    format!("world: {}{given}\n", values.join(" "))
}

pub use needle_scenario::reserve::reserve_line;

/// The table of a simulation.
pub fn to_table(h: &Header<'_>, p: &Perturbation, s: &Summary) -> String {
    let mut out = String::new();
    h.title(&mut out, "open-loop");
    heads(&mut out, "(mm)");
    let _ = writeln!(out);
    row(&mut out, "target error", &s.target_error);
    row(&mut out, "path deviation, run RMS", &s.path_rms);
    row(&mut out, "path deviation, run max", &s.path_max);
    if let (Some(rms), Some(max)) = (&s.path_rms_in_plane, &s.path_max_in_plane) {
        row(&mut out, "  in the plane, run RMS", rms);
        row(&mut out, "  in the plane, run max", max);
    }
    let clear = if s.min_clearance.is_finite() {
        format!("{:.3} mm", s.min_clearance)
    } else {
        "no obstacles".into()
    };
    let _ = writeln!(
        out,
        "collisions: {} of {} runs; smallest clearance {clear}",
        s.collisions, h.runs
    );
    voxels_line(&mut out, s, h.runs);
    rotations_line(&mut out, &s.rotations);
    perturbation_line(&mut out, p);
    out
}

/// With `[[anatomy]]`: the runs whose true path entered an organ's voxels.
fn voxels_line(out: &mut String, s: &Summary, runs: usize) {
    if let Some(n) = s.entered_voxels {
        let _ = writeln!(
            out,
            "against the label map: {n} of {runs} runs' true paths entered a voxel of the \
             covered segments (counted in the collisions; the clearance is to the spheres)"
        );
    }
}

/// The bevel rotations per insertion.
fn rotations_line(out: &mut String, r: &super::RotationFigures) {
    let smallest = r
        .smallest_deg
        .map_or_else(|| "none".to_string(), |d| format!("{d:.2} deg"));
    let _ = writeln!(
        out,
        "bevel rotations per insertion: median {}, most {}, {:.0} deg in all on average; \
         smallest {smallest}",
        r.median_per_run, r.max_per_run, r.mean_total_deg
    );
}

/// A row of spreads, with the open loop's beside it when given.
fn pair(out: &mut String, what: &str, closed: &Spread, open: Option<&Spread>) {
    let _ = write!(
        out,
        "{what:<28}{:>9.3}{:>9.3}{:>9.3}{:>9.3}",
        closed.mean, closed.rms, closed.p95, closed.max
    );
    if let Some(o) = open {
        let _ = write!(
            out,
            "   |{:>9.3}{:>9.3}{:>9.3}{:>9.3}",
            o.mean, o.rms, o.p95, o.max
        );
    }
    let _ = writeln!(out);
}

/// The table of a closed-loop simulation, with the open loop beside it when given.
pub fn closed_table(
    h: &Header<'_>,
    p: &Perturbation,
    s: &Summary,
    steering: &SteeringSummary,
    open: Option<&Summary>,
) -> String {
    let mut out = String::new();
    h.title(&mut out, "closed-loop");
    heads(&mut out, "closed loop (mm)");
    if open.is_some() {
        let _ = write!(
            out,
            "   |{:>9}{:>9}{:>9}{:>9}",
            "open:mean", "rms", "p95", "max"
        );
    }
    let _ = writeln!(out);
    pair(
        &mut out,
        "target error",
        &s.target_error,
        open.map(|o| &o.target_error),
    );
    pair(
        &mut out,
        "  the runs that reached",
        &steering.reached_target_error,
        None,
    );
    pair(
        &mut out,
        "path deviation, run RMS",
        &s.path_rms,
        open.map(|o| &o.path_rms),
    );
    pair(
        &mut out,
        "path deviation, run max",
        &s.path_max,
        open.map(|o| &o.path_max),
    );
    let clear = |c: f32| {
        if c.is_finite() {
            format!("{c:.3} mm")
        } else {
            "no obstacles".into()
        }
    };
    let _ = write!(
        out,
        "collisions: {} of {} runs; smallest clearance {}",
        s.collisions,
        h.runs,
        clear(s.min_clearance)
    );
    if let Some(o) = open {
        let _ = write!(
            out,
            "   (open loop: {} collisions; smallest clearance {})",
            o.collisions,
            clear(o.min_clearance)
        );
    }
    let _ = writeln!(out);
    voxels_line(&mut out, s, h.runs);
    rotations_line(&mut out, &s.rotations);
    steering_lines(&mut out, h.runs, steering);
    let _ = writeln!(
        out,
        "within the tissue's reach: {} of {} runs (its full curvature, turned at the target from \
         the entry, comes within the reach tolerance); {} of them reached",
        steering.within_reach, h.runs, steering.reached_within_reach
    );
    let _ = writeln!(
        out,
        "tracker: {} outliers rejected, {} readings without a fix, {} stale, {} repeated",
        steering.outliers, steering.no_fix, steering.stale, steering.repeated
    );
    let _ = writeln!(
        out,
        "target: {} imaged targets rejected as outliers, {} moves followed",
        steering.target_outliers, steering.target_jumps
    );
    perturbation_line(&mut out, p);
    out
}

/// How the steered runs ended (the world's judgement), then the controller's own.
fn steering_lines(out: &mut String, runs: usize, steering: &SteeringSummary) {
    let stops: Vec<String> = steering
        .stops
        .iter()
        .map(|(k, v)| format!("{k} {v}"))
        .collect();
    let outcome = |name: &str| steering.outcomes.get(name).copied().unwrap_or(0);
    let _ = writeln!(
        out,
        "outcomes: {} of {} runs reached the target, {} missed, {} collided, {} stopped \
         (judged on the true tip, within the reach tolerance, and the true path)",
        steering.reached,
        runs,
        outcome("missed"),
        outcome("collided"),
        outcome("stopped"),
    );
    let _ = writeln!(
        out,
        "steering: the controller judged {} of {} runs at the target; {} replans, {} replan \
         failures; stops before the target: {}",
        steering.controller_reached,
        runs,
        steering.replans,
        steering.replan_failures,
        stops.join(", ")
    );
}
