//! A core [`Scenario`] written as a scenario file (the format of `examples/paper.toml`), every
//! key explicit, so that `needle plan` reads back exactly the scenario written and plans it as
//! `planner_core::plan` does (unbounded, for the schedule as planned).

use planner_core::model::scenario::{RiskMeasure, Workspace};
use planner_core::Scenario;
use std::fmt::Write;

/// A number as TOML reads it back to the same `f32`: Rust's shortest round-trip digits, which
/// always carry a decimal point or an exponent (a TOML float, never an integer).
fn num(v: f32) -> String {
    format!("{v:?}")
}

fn vector(v: [f32; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

/// The TOML text of `scenario`, named `name` (a free-form comment line `header` on top).
pub fn scenario_toml(scenario: &Scenario, name: &str, header: &str) -> String {
    let s = scenario;
    let mut out = String::new();
    for line in header.lines() {
        let _ = writeln!(out, "# {line}");
    }
    let _ = writeln!(out, "name = {name:?}\n");
    let n = &s.needle;
    let _ = writeln!(out, "[needle]");
    let _ = writeln!(out, "curvature_radius = {}", num(n.curvature_radius));
    let _ = writeln!(out, "max_arc_deg = {}", num(n.max_arc_deg));
    let _ = writeln!(
        out,
        "max_line_length = {}   # 0: twice the entry-target distance plus a half turn",
        num(n.max_line_length)
    );
    let _ = writeln!(out, "length = {}   # insertable length\n", num(n.length));
    let e = &s.entry;
    let _ = writeln!(out, "[entry]");
    let _ = writeln!(out, "position = {}", vector(e.position));
    let _ = writeln!(out, "direction = {}", vector(e.direction));
    let _ = writeln!(out, "max_tilt_deg = {}\n", num(e.max_tilt_deg));
    let _ = writeln!(out, "[target]");
    let _ = writeln!(out, "position = {}", vector(s.target.position));
    let _ = writeln!(out, "tolerance = {}\n", num(s.target.tolerance));
    for o in &s.obstacles {
        let _ = writeln!(out, "[[obstacles]]");
        let _ = writeln!(out, "center = {}", vector(o.center));
        let _ = writeln!(out, "radius = {}\n", num(o.radius));
    }
    let w = &s.weights;
    let _ = writeln!(out, "[weights]");
    let _ = writeln!(out, "length = {}", num(w.length));
    let _ = writeln!(out, "risk = {}", num(w.risk));
    let _ = writeln!(out, "penalty = {}", num(w.penalty));
    let _ = writeln!(out, "control = {}\n", num(w.control));
    let p = &s.options;
    let _ = writeln!(out, "[planner]");
    let _ = writeln!(out, "max_control_degree = {}", p.max_control_degree);
    if p.workspace == Workspace::PlaneYz {
        let _ = writeln!(out, "plane = \"yz\"");
    }
    if !p.forms.is_empty() {
        let words: Vec<String> = p.forms.iter().map(|f| format!("\"{f}\"")).collect();
        let _ = writeln!(out, "forms = [{}]", words.join(", "));
    }
    let risk = match p.risk {
        RiskMeasure::Mean => "mean",
        RiskMeasure::Sum => "sum",
    };
    let _ = writeln!(out, "risk = \"{risk}\"");
    let _ = writeln!(out, "min_clearance = {}", num(p.min_clearance));
    // Always written: a file silent on it keeps the closed loop's default reserve.
    let _ = writeln!(out, "curvature_reserve = {}", num(p.curvature_reserve));
    if let Some(r) = p.risk_within_mm {
        let _ = writeln!(out, "risk_within_mm = {}", num(r));
    }
    let _ = writeln!(out);
    // The core's scenario knows no bound and no mode: it plans unbounded, for the schedule as
    // planned, and a file silent on them would plan for steering under a bound instead.
    let _ = writeln!(out, "max_collision_probability = \"off\"\n");
    let d = &s.driver;
    let _ = writeln!(out, "[driver]");
    let _ = writeln!(out, "insert_speed = {}", num(d.insert_speed));
    let _ = writeln!(out, "rotate_speed = {}", num(d.rotate_speed));
    let _ = writeln!(out, "spin_rate = {}", num(d.spin_rate));
    let _ = writeln!(out, "max_twist_deg = {}", num(d.max_twist_deg));
    let _ = writeln!(out, "\n[execution]\nmode = \"open_loop\"");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unseen::unseen_scenario;
    use crate::ScenarioFile;
    use planner_core::model::form::Form;
    use planner_core::model::scenario::RiskMeasure;

    fn read_back(s: &Scenario) -> Scenario {
        let text = scenario_toml(s, "probe", "a scenario\nwritten by a test");
        ScenarioFile::parse(&text).unwrap().to_scenario().unwrap()
    }

    #[test]
    fn written_scenarios_read_back_equal() {
        for seed in 0..40 {
            let s = unseen_scenario(seed);
            assert_eq!(read_back(&s), s, "seed {seed}");
        }
        let mut s = Scenario::paper();
        assert_eq!(read_back(&s), s);
        s.options.workspace = Workspace::Space;
        s.options.risk = RiskMeasure::Sum;
        s.options.forms.insert(Form::parse("RL").unwrap());
        s.options.forms.insert(Form::parse("LRL").unwrap());
        s.options.min_clearance = 0.25;
        s.needle.max_line_length = 123.456;
        s.needle.length = 1500.5;
        s.target.position = [1e-7, -3.3, 1e3];
        assert_eq!(read_back(&s), s);
    }
}
