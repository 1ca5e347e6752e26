//! The table `needle benchmark` prints: one row per scenario, the totals, the scenarios left out.

use super::{BenchmarkArgs, BenchmarkReport, ClosedFigures, OpenFigures};
use std::fmt::Write;

/// A millimetre figure, or a dash when there is none.
fn mm(v: Option<f64>) -> String {
    v.map_or_else(|| "-".to_string(), |v| format!("{v:.2}"))
}

/// The open- and closed-loop columns.
fn figures(out: &mut String, o: &OpenFigures, c: &ClosedFigures) {
    let _ = writeln!(
        out,
        " |{:>7.1}{:>8.2} |{:>10.1}{:>7}{:>6}{:>8}{:>8}",
        o.hit_percent,
        o.mean_target_error,
        c.reached_percent,
        c.stops,
        c.hits,
        mm(c.mean_target_error),
        mm(c.p95_target_error)
    );
}

/// The benchmark's table.
pub fn to_table(a: &BenchmarkArgs, r: &BenchmarkReport) -> String {
    let mut out = String::new();
    let last = a.seed.wrapping_add((a.scenarios as u64).saturating_sub(1));
    let _ = writeln!(
        out,
        "unseen 3-D scenarios, seeds {}..={last}: {} simulated worlds each, open loop and the \
         same worlds closed loop",
        a.seed, a.runs
    );
    let groups = format!("{:<50} |{:^15} |{:^39}", "", "open loop", "closed loop");
    let _ = writeln!(out, "{}", groups.trim_end());
    let _ = writeln!(
        out,
        "{:>6}{:>8}{:>10}{:>6}{:>10}{:>10} |{:>7}{:>8} |{:>10}{:>7}{:>6}{:>8}{:>8}",
        "seed",
        "spheres",
        "target mm",
        "form",
        "length",
        "clearance",
        "hit %",
        "error",
        "reached %",
        "stops",
        "hits",
        "error",
        "p95"
    );
    for row in &r.scenarios {
        let _ = write!(
            out,
            "{:>6}{:>8}{:>10.1}{:>6}{:>10.1}{:>10.2}",
            row.seed,
            row.spheres,
            row.target_distance,
            row.form,
            row.plan_length,
            row.plan_clearance
        );
        figures(&mut out, &row.open_loop, &row.closed_loop);
    }
    let t = &r.totals;
    let _ = write!(
        out,
        "{:<50}",
        format!("total: {} scenarios, {} runs", t.planned, t.runs)
    );
    figures(&mut out, &t.open_loop, &t.closed_loop);
    let reasons: Vec<String> = t
        .closed_loop
        .stop_reasons
        .iter()
        .filter(|(_, n)| **n > 0)
        .map(|(reason, n)| format!("{reason} {n}"))
        .collect();
    if !reasons.is_empty() {
        let _ = writeln!(out, "closed-loop stops: {}", reasons.join(", "));
    }
    let _ = writeln!(
        out,
        "errors in mm (closed loop: of the runs that arrived); hits: runs that entered a sphere"
    );
    let _ = writeln!(
        out,
        "not benchmarked: {} of {} scenarios",
        t.unplanned, t.scenarios
    );
    for u in &r.unplanned {
        let _ = writeln!(
            out,
            "  seed {} ({} spheres): {}",
            u.seed, u.spheres, u.reason
        );
    }
    out
}
