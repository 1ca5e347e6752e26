//! Structure-aware planner target: arbitrary scenarios, inside and far outside the valid ranges,
//! through the validation the device runs, checked by the f64 reference (`needle_e2e::soundness`):
//! no panic, refusals equal to validation's, every reported path sound, work under a bound.
//!
//! Each number is a [`Num`]: mostly a value inside a sane range (so the planner does real work),
//! sometimes the field's default, sometimes any f32 at all (NaN, infinities, 1e38, subnormals).

#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use needle_e2e::soundness::check_plan;
use planner_core::model::form::FormSet;
use planner_core::model::scenario::{Obstacle, RiskMeasure, Workspace};
use planner_core::Scenario;

#[derive(Arbitrary, Debug, Clone, Copy)]
struct Num {
    how: u8,
    fraction: u16,
    raw: f32,
}

impl Num {
    /// A value in `lo..=hi` (linear), the default, or (1 in 16) the raw f32.
    fn pick(self, lo: f32, hi: f32, default: f32) -> f32 {
        match self.how % 16 {
            0 => self.raw,
            1 | 2 => default,
            _ => lo + (hi - lo) * f32::from(self.fraction) / f32::from(u16::MAX),
        }
    }

    /// As `pick`, spread evenly over the decades of `lo..=hi` (tolerances, small radii).
    fn pick_log(self, lo: f32, hi: f32, default: f32) -> f32 {
        match self.how % 16 {
            0 | 1 | 2 => self.pick(lo, hi, default),
            _ => libm::powf(10.0, self.pick(libm::log10f(lo), libm::log10f(hi), default)),
        }
    }
}

#[derive(Arbitrary, Debug)]
struct Input {
    radius: Num,
    max_arc: Num,
    max_line: Num,
    entry: [Num; 3],
    direction: [Num; 3],
    tilt: Num,
    target: [Num; 3],
    tolerance: Num,
    obstacles: Vec<([Num; 3], Num)>,
    weights: [Num; 4],
    degree: u8,
    forms: u64,
    explicit_forms: bool,
    plane: bool,
    sum_risk: bool,
    min_clearance: Num,
    driver: [Num; 4],
}

fn scenario(i: &Input) -> Scenario {
    let mut s = Scenario::paper();
    let d = s.clone();
    s.needle.curvature_radius = i.radius.pick_log(5.0, 500.0, d.needle.curvature_radius);
    s.needle.max_arc_deg = i.max_arc.pick(1.0, 360.0, d.needle.max_arc_deg);
    s.needle.max_line_length = i.max_line.pick(1.0, 300.0, d.needle.max_line_length);
    for k in 0..3 {
        s.entry.position[k] = i.entry[k].pick(-20.0, 20.0, d.entry.position[k]);
        s.entry.direction[k] = i.direction[k].pick(-1.0, 1.0, d.entry.direction[k]);
    }
    s.entry.max_tilt_deg = i.tilt.pick(0.0, 90.0, d.entry.max_tilt_deg);
    let ahead = [(-60.0, 60.0), (-60.0, 60.0), (10.0, 160.0)];
    for (k, (lo, hi)) in ahead.into_iter().enumerate() {
        s.target.position[k] = i.target[k].pick(lo, hi, d.target.position[k]);
    }
    s.target.tolerance = i.tolerance.pick_log(1e-5, 5.0, d.target.tolerance);
    s.obstacles.clear();
    for (c, r) in &i.obstacles {
        let center = [
            c[0].pick(-40.0, 40.0, 0.0),
            c[1].pick(-40.0, 40.0, 0.0),
            c[2].pick(0.0, 120.0, 50.0),
        ];
        let radius = r.pick_log(0.1, 40.0, 10.0);
        if s.obstacles.push(Obstacle { center, radius }).is_err() {
            break; // the type's capacity; a longer list is the wire's concern (service target)
        }
    }
    let w = d.weights;
    s.weights.length = i.weights[0].pick(0.0, 5.0, w.length);
    s.weights.risk = i.weights[1].pick(0.0, 10.0, w.risk);
    s.weights.penalty = i.weights[2].pick(0.0, 2000.0, w.penalty);
    s.weights.control = i.weights[3].pick(0.0, 10.0, w.control);
    s.options.max_control_degree = i.degree % 6;
    let mut forms = FormSet::default();
    for (k, form) in planner_core::model::form::catalogue()
        .into_iter()
        .enumerate()
    {
        if i.forms.checked_shr(k as u32).unwrap_or(0) & 1 != 0 {
            forms.insert(form);
        }
    }
    // Most inputs plan every form up to the degree (the default); some a chosen subset.
    if i.explicit_forms {
        s.options.forms = forms;
    }
    s.options.workspace = if i.plane {
        Workspace::PlaneYz
    } else {
        Workspace::Space
    };
    if i.plane {
        // Mostly a true plane problem; sometimes off the plane (validation's business).
        if i.entry[0].how % 4 != 0 {
            s.target.position[0] = 0.0;
            s.obstacles.iter_mut().for_each(|o| o.center[0] = 0.0);
        }
    }
    s.options.risk = if i.sum_risk {
        RiskMeasure::Sum
    } else {
        RiskMeasure::Mean
    };
    s.options.min_clearance = i.min_clearance.pick(0.0, 5.0, 0.0);
    let v = d.driver;
    s.driver.insert_speed = i.driver[0].pick_log(0.01, 100.0, v.insert_speed);
    s.driver.rotate_speed = i.driver[1].pick_log(1.0, 5000.0, v.rotate_speed);
    s.driver.spin_rate = i.driver[2].pick_log(0.05, 50.0, v.spin_rate);
    s.driver.max_twist_deg = i.driver[3].pick(0.0, 3600.0, v.max_twist_deg);
    s
}

fuzz_target!(|input: Input| {
    let s = scenario(&input);
    if let Err(why) = check_plan(&s) {
        panic!("{why}\nscenario: {s:?}");
    }
});
