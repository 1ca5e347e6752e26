//! The table `needle simulate` prints.

use super::{Spread, Summary};
use hil_sim::insertion::{Perturbation, KEYS};
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

fn row(out: &mut String, what: &str, s: &Spread) {
    let _ = writeln!(
        out,
        "{what:<28}{:>9.3}{:>9.3}{:>9.3}{:>9.3}",
        s.mean, s.rms, s.p95, s.max
    );
}

/// The table of a simulation.
pub fn to_table(h: &Header<'_>, p: &Perturbation, s: &Summary) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "simulated open-loop insertions of {} in {}: {} runs, seeds {}..",
        h.form, h.file, h.runs, h.seed
    );
    let _ = writeln!(
        out,
        "{:<28}{:>9}{:>9}{:>9}{:>9}",
        "(mm)", "mean", "rms", "p95", "max"
    );
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
    let values: Vec<String> = KEYS
        .iter()
        .map(|k| format!("{k}={}", p.get(k).unwrap_or(f32::NAN)))
        .collect();
    let _ = writeln!(out, "perturbation: {}", values.join(" "));
    out
}
