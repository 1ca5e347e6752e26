//! `needle bench`: how long planning a scenario takes on this machine, and the solver's effort
//! per form. Runs are sequential on one thread; the figure reported is the median.

use planner_core::{plan, PlanReport, Scenario};
use serde_json::{json, Value};
use std::time::Instant;

/// Timing of repeated plans of one scenario.
pub struct BenchResult {
    /// Wall-clock time of each run (µs), sorted.
    pub times_us: Vec<f64>,
    /// The (identical) report of every run.
    pub report: PlanReport,
}

impl BenchResult {
    /// Median run time (µs).
    pub fn median_us(&self) -> f64 {
        let t = &self.times_us;
        let n = t.len();
        if n % 2 == 1 {
            t[n / 2]
        } else {
            (t[n / 2 - 1] + t[n / 2]) / 2.0
        }
    }
}

/// Plans `scenario` `runs` times (after `warmup` unmeasured runs).
pub fn run(scenario: &Scenario, warmup: usize, runs: usize) -> anyhow::Result<BenchResult> {
    let mut report = plan(scenario)?;
    for _ in 0..warmup {
        report = plan(scenario)?;
    }
    let mut times_us = Vec::with_capacity(runs.max(1));
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let r = plan(scenario)?;
        times_us.push(t.elapsed().as_secs_f64() * 1e6);
        std::hint::black_box(&r);
    }
    times_us.sort_by(f64::total_cmp);
    Ok(BenchResult { times_us, report })
}

/// Human-readable summary.
pub fn table(name: &str, r: &BenchResult) -> String {
    let mut s = format!(
        "{name}: {} runs, median {:.1} us, min {:.1} us, max {:.1} us\n",
        r.times_us.len(),
        r.median_us(),
        r.times_us[0],
        r.times_us[r.times_us.len() - 1]
    );
    s.push_str(&format!(
        "{:<5} {:>10} {:>12}\n",
        "form", "iterations", "evaluations"
    ));
    for o in &r.report.forms {
        s.push_str(&format!(
            "{:<5} {:>10} {:>12}\n",
            o.form.to_string(),
            o.iterations,
            o.evaluations
        ));
    }
    s.push_str(&format!(
        "{:<5} {:>10} {:>12}\n",
        "total",
        r.report.iterations(),
        r.report.evaluations()
    ));
    s
}

/// JSON summary.
pub fn to_json(name: &str, r: &BenchResult) -> Value {
    json!({
        "scenario": name,
        "runs": r.times_us.len(),
        "median_us": r.median_us(),
        "min_us": r.times_us[0],
        "max_us": r.times_us[r.times_us.len() - 1],
        "forms": r.report.forms.iter().map(|o| json!({
            "form": o.form.to_string(),
            "iterations": o.iterations,
            "evaluations": o.evaluations,
        })).collect::<Vec<_>>(),
    })
}

/// Two scenarios planned side by side (alternating, one thread): the far spheres' cost.
pub struct SideBySide {
    /// Median plan time with every sphere (ms).
    pub all_ms: f64,
    /// Median plan time with the near spheres alone (ms).
    pub near_ms: f64,
    /// The best form both plans have.
    pub best: String,
}

/// Median of `t` (ms; not empty).
fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    let n = t.len();
    if n % 2 == 1 {
        t[n / 2]
    } else {
        (t[n / 2 - 1] + t[n / 2]) / 2.0
    }
}

/// Plans [`crate::scale::near_and_far`]`(seed, total, near)` and its near spheres alone `runs`
/// times each, alternating: an error unless the two are the same plan (the far spheres lie
/// beyond the risk term's reach), else both medians.
pub fn near_and_far(
    seed: u64,
    total: usize,
    near: usize,
    runs: usize,
) -> anyhow::Result<SideBySide> {
    use crate::scale::{near_and_far, plan_difference, NearFar};
    anyhow::ensure!(
        near >= 1 && near <= total && total <= planner_core::MAX_OBSTACLES,
        "--near-and-far {total},{near}: NEAR from 1 to TOTAL, TOTAL at most {}",
        planner_core::MAX_OBSTACLES
    );
    let NearFar { all, near_alone } = near_and_far(seed, total, near);
    let (a, b) = (plan(&all)?, plan(&near_alone)?);
    if let Some(d) = plan_difference(&a, &b) {
        anyhow::bail!("the plans differ: {d}");
    }
    let (mut t_all, mut t_near) = (Vec::new(), Vec::new());
    for _ in 0..runs.max(1) {
        for (s, times) in [(&all, &mut t_all), (&near_alone, &mut t_near)] {
            let t = Instant::now();
            let r = plan(s)?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(&r);
        }
    }
    Ok(SideBySide {
        all_ms: median(t_all),
        near_ms: median(t_near),
        best: a.best().map_or("none".into(), |o| o.form.to_string()),
    })
}

/// Median times (µs) of one measure of a plan: with every sphere (culled as the planner does),
/// with every sphere measured in full (the exhaustive reference), with the near spheres alone.
#[derive(Clone, Copy, Debug)]
pub struct Measure {
    pub culled_us: f64,
    pub every_us: f64,
    pub near_us: f64,
}

/// The check's clearances (each path rebuilt from the plan's numbers, then measured), the
/// collision-risk spread (open loop, the default perturbation) and the steering's prediction
/// (the schedule from the posture) of every feasible form of the plan both scenarios share,
/// timed side by side `runs` times; an error unless the culled and the exhaustive figures agree
/// bit for bit.
pub struct Measures {
    pub check: Measure,
    pub risk: Measure,
    pub predict: Measure,
    /// Feasible forms measured.
    pub forms: usize,
}

/// Times `f` on each of the three inputs, alternating; the median of each (µs).
/// `f` of 0 (culled), 1 (every sphere) and 2 (the near alone), timed side by side, after
/// checking that the culled and the full answers are the same bits.
fn culled_and_full<T: PartialEq>(
    what: &str,
    runs: usize,
    mut f: impl FnMut(usize) -> T,
) -> anyhow::Result<Measure> {
    anyhow::ensure!(f(0) == f(1), "the culled {what} differs");
    let [culled_us, every_us, near_us] = side_by_side(runs, f);
    Ok(Measure {
        culled_us,
        every_us,
        near_us,
    })
}

fn side_by_side<T>(runs: usize, mut f: impl FnMut(usize) -> T) -> [f64; 3] {
    let mut t: [Vec<f64>; 3] = Default::default();
    for _ in 0..runs.max(1) {
        for (k, times) in t.iter_mut().enumerate() {
            let start = Instant::now();
            std::hint::black_box(f(k));
            times.push(start.elapsed().as_secs_f64() * 1e6);
        }
    }
    t.map(median)
}

/// [`Measures`] of `near_and_far(seed, total, near)`'s plan.
pub fn measures(seed: u64, total: usize, near: usize, runs: usize) -> anyhow::Result<Measures> {
    use planner_core::check::{clearances, clearances_of, rebuild};
    use planner_core::execute::{nominal::posture_frame, perturbation::Perturbation};
    use planner_core::execute::{risk::risk_measuring, risk::Execution, schedule::schedule};
    use planner_core::model::broad::{Broad, Set};
    use planner_core::steer::replan::predict_with;
    let crate::scale::NearFar { all, near_alone } = crate::scale::near_and_far(seed, total, near);
    let report = plan(&all)?;
    let mut forms = Vec::new();
    for o in report.forms.iter().filter(|o| o.feasible) {
        forms.push((o, schedule(&all, o)?));
    }
    let scenarios = [&all, &all, &near_alone];
    let every = Set::all(all.obstacles.len());
    let check_of = |k: usize| {
        let mut bits = Vec::new();
        for (o, _) in &forms {
            let geo = rebuild(scenarios[k], o.form, &o.insertion, &o.segments);
            let (least, sum) = if k == 1 {
                clearances_of(&all, &geo, &every)
            } else {
                clearances(scenarios[k], &geo)
            };
            bits.push((least.to_bits(), sum.to_bits()));
        }
        bits
    };
    let check = culled_and_full("clearances", runs, check_of)?;
    let p = Perturbation::default();
    let mut by = [Default::default(); planner_core::MAX_OBSTACLES];
    let risk_of = |k: usize| {
        let mut bits = Vec::new();
        for (_, s) in &forms {
            let r = risk_measuring(scenarios[k], s, &p, Execution::OpenLoop, &mut by, k != 1);
            bits.push((
                r.collision_probability.to_bits(),
                r.target_error_p95.to_bits(),
            ));
        }
        bits
    };
    let risk = culled_and_full("risk", runs, risk_of)?;
    let radius = all.needle.curvature_radius;
    let t = all.target.position;
    let target = planner_core::model::kinematics::V3::new(t[0], t[1], t[2]);
    let trees = [
        Broad::new(&all.obstacles),
        Broad::new(&near_alone.obstacles),
    ];
    let predict_of = |k: usize| {
        let tree = [Some(&trees[0]), None, Some(&trees[1])][k];
        let mut bits = Vec::new();
        for (_, s) in &forms {
            let tip = posture_frame(&all, s);
            let p = predict_with(scenarios[k], tree, &tip, &s.steps, radius, target);
            bits.push(p.min_clearance.to_bits());
        }
        bits
    };
    let predict = culled_and_full("prediction", runs, predict_of)?;
    Ok(Measures {
        check,
        risk,
        predict,
        forms: forms.len(),
    })
}
