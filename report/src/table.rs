//! The `needle plan` table: one row per form, then the overall best.

use super::json::Stats;
use planner_core::PlanReport;

fn cell(v: f32, feasible: bool, prec: usize) -> String {
    if feasible && v.is_finite() {
        format!("{v:.prec$}")
    } else {
        "-".to_string()
    }
}

/// The human-readable table: one row per form, then the overall best.
pub fn plan_table(report: &PlanReport, stats: Stats) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "{:<5} {:>3} {:>8} {:>9} {:>8} {:>9} {:>10} {:>12}  {}\n",
        "form", "N", "feasible", "L (mm)", "D", "F", "clear (mm)", "target (mm)", "status"
    ));
    for o in &report.forms {
        let f = o.feasible;
        s.push_str(&format!(
            "{:<5} {:>3} {:>8} {:>9} {:>8} {:>9} {:>10} {:>12}  {:?}\n",
            o.form.to_string(),
            o.form.len(),
            if f { "yes" } else { "no" },
            cell(o.length, f, 2),
            cell(o.risk, f, 4),
            cell(o.objective, f, 3),
            cell(o.min_clearance, f, 2),
            cell(o.target_error, f, 5),
            o.status,
        ));
    }
    if let Some(b) = report.best() {
        s.push_str(&format!(
            "\nbest: {} (N = {}), F = {:.3}, L = {:.2} mm, D = {:.4}, insertion tilt {:.2} deg\n",
            b.form,
            b.form.len(),
            b.objective,
            b.length,
            b.risk,
            b.insertion.tilt_deg
        ));
        for (i, seg) in b.segments.iter().enumerate() {
            s.push_str(&format!(
                "  segment {}: {} {:.2} mm, bevel {:.1} deg\n",
                i + 1,
                seg.kind.letter(),
                seg.length,
                seg.bevel_deg
            ));
        }
    }
    s.push_str(&format!(
        "planned in {} us, {} iterations, {} evaluations\n",
        stats.time_us,
        report.iterations(),
        report.evaluations()
    ));
    s
}
