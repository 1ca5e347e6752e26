//! The table `needle benchmark` prints: one row per scenario, the totals, the scenarios left out.

use super::{BenchmarkOptions, BenchmarkReport, ClosedFigures, OpenFigures};
use std::fmt::Write;

/// A millimetre figure, or a dash when there is none.
fn mm(v: Option<f64>) -> String {
    v.map_or_else(|| "-".to_string(), |v| format!("{v:.2}"))
}

/// The open- and closed-loop columns (dashes for a closed loop not run).
fn figures(
    out: &mut String,
    predicted: Option<f64>,
    o: Option<&OpenFigures>,
    c: Option<&ClosedFigures>,
) {
    let predicted = predicted.map_or_else(|| "-".to_string(), |p| format!("{:.1}", 100.0 * p));
    let _ = match o {
        Some(o) => write!(
            out,
            " |{:>7.1}{:>8}{:>8.2}{:>8.2} |",
            o.hit_percent, predicted, o.mean_target_error, o.p95_target_error
        ),
        None => write!(out, " |{:>7}{:>8}{:>8}{:>8} |", "-", "-", "-", "-"),
    };
    let _ = match c {
        Some(c) => writeln!(
            out,
            "{:>10.1}{:>7}{:>6}{:>8}{:>8}",
            c.reached_percent,
            c.stops,
            c.hits,
            mm(c.mean_target_error),
            mm(c.p95_target_error)
        ),
        None => writeln!(out, "{:>10}{:>7}{:>6}{:>8}{:>8}", "-", "-", "-", "-", "-"),
    };
}

/// The totals of the scenarios planned with each form.
fn by_form(out: &mut String, r: &BenchmarkReport) {
    let _ = writeln!(
        out,
        "by planned form (open loop: scenarios planned so; closed loop: scenarios steered so):"
    );
    for (form, t) in &r.by_form {
        let _ = write!(
            out,
            "{:<50}",
            format!(
                "  {form}: {} open / {} closed scenarios",
                t.scenarios, t.closed_loop_scenarios
            )
        );
        figures(out, None, t.open_loop.as_ref(), t.closed_loop.as_ref());
    }
}

/// The plans steered closed loop, where they differ from the open-loop plan.
fn steered_plans(out: &mut String, asked: f32, r: &BenchmarkReport) {
    let _ = writeln!(
        out,
        "closed loop steers plans keeping curvature reserve {asked} (less where no path keeps it):"
    );
    for row in &r.scenarios {
        if let Some(p) = &row.closed_loop_plan {
            let _ = writeln!(
                out,
                "  seed {}: {} {:.1} mm, clearance {:.2} mm, reserve {}, predicted {:.2} %",
                row.seed,
                p.form,
                p.plan_length,
                p.plan_clearance,
                p.curvature_reserve,
                100.0 * p.predicted_collision_probability
            );
        }
        if let Some(reason) = &row.closed_loop_refused {
            let _ = writeln!(out, "  seed {}: not steered: {reason}", row.seed);
        }
    }
}

/// The safe plans' lengths against the unbounded ones.
fn length_costs(out: &mut String, bound: f32, r: &BenchmarkReport) {
    let _ = writeln!(
        out,
        "planned under max_collision_probability = {bound}; cost in length of the safe plans:"
    );
    for row in &r.scenarios {
        if let Some(free) = row.predicted.unbounded_length {
            let _ = writeln!(
                out,
                "  seed {}: {:.1} mm against {:.1} mm unbounded ({:+.1} mm)",
                row.seed,
                row.plan_length,
                free,
                f64::from(row.plan_length) - free
            );
        }
    }
}

/// The table's first lines: the family, the world and what the controller was told.
fn heading(out: &mut String, a: &BenchmarkOptions, r: &BenchmarkReport) {
    let last = a.seed.wrapping_add((a.scenarios as u64).saturating_sub(1));
    let _ = writeln!(
        out,
        "{} 3-D scenarios, seeds {}..={last}: {} simulated worlds each, open loop and the \
         same worlds closed loop",
        a.generator.name(),
        a.seed,
        a.runs
    );
    out.push_str(&crate::table::world_line(&r.world));
    if !a.faults.is_empty() || !a.steer.is_empty() {
        let told: Vec<&str> = a
            .faults
            .iter()
            .chain(&a.steer)
            .map(String::as_str)
            .collect();
        let _ = writeln!(
            out,
            "faults and steering (over the world's): {}",
            told.join(" ")
        );
    }
}

/// The benchmark's table.
pub fn to_table(a: &BenchmarkOptions, r: &BenchmarkReport) -> String {
    let mut out = String::new();
    heading(&mut out, a, r);
    let groups = format!("{:<50} |{:^31} |{:^39}", "", "open loop", "closed loop");
    let _ = writeln!(out, "{}", groups.trim_end());
    let _ = writeln!(
        out,
        "{:>6}{:>8}{:>10}{:>6}{:>10}{:>10} |{:>7}{:>8}{:>8}{:>8} |{:>10}{:>7}{:>6}{:>8}{:>8}",
        "seed",
        "spheres",
        "target mm",
        "form",
        "length",
        "clearance",
        "hit %",
        "pred %",
        "error",
        "p95",
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
        let predicted = Some(row.predicted.collision_probability);
        figures(
            &mut out,
            predicted,
            Some(&row.open_loop),
            row.closed_loop.as_ref(),
        );
    }
    let t = &r.totals;
    let _ = write!(
        out,
        "{:<50}",
        format!("total: {} scenarios, {} runs", t.planned, t.runs)
    );
    let predicted = Some(t.predicted_collision_probability);
    figures(
        &mut out,
        predicted,
        Some(&t.open_loop),
        t.closed_loop.as_ref(),
    );
    closed_totals(&mut out, t.closed_loop.as_ref());
    let _ = writeln!(
        out,
        "errors in mm (closed loop: of the runs that arrived); hits: runs that entered a sphere; \
         pred %: the planner's predicted collision probability (first order)"
    );
    by_form(&mut out, r);
    if !a.open_loop_only {
        steered_plans(&mut out, a.curvature_reserve, r);
    }
    if let Some(bound) = a.max_collision_probability {
        length_costs(&mut out, bound, r);
    }
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

/// The closed loop's totals beyond the row: stops by reason, outcomes, the tissue's reach.
fn closed_totals(out: &mut String, closed: Option<&ClosedFigures>) {
    let reasons: Vec<String> = closed
        .iter()
        .flat_map(|c| c.stop_reasons.iter())
        .filter(|(_, n)| **n > 0)
        .map(|(reason, n)| format!("{reason} {n}"))
        .collect();
    if !reasons.is_empty() {
        let _ = writeln!(out, "closed-loop stops: {}", reasons.join(", "));
    }
    if let Some(c) = closed {
        let _ = writeln!(
            out,
            "closed-loop outcomes: {} reached, {} missed, {} collided, {} stopped (the true tip \
             and path; reached %: of every run)",
            c.reached, c.missed, c.collided, c.stopped
        );
        let _ = writeln!(
            out,
            "closed loop: {} runs within the tissue's reach, {} of them reached",
            c.within_reach, c.reached_within_reach
        );
    }
}
