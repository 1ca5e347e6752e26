//! The host's re-check of the schedule a device sends with its plan: the device's schedule must
//! pass the nominal model's execution (`execute::nominal::check`) and equal, bit for bit, the
//! schedule the host builds from the same report. `needle send` refuses anything else.

use anyhow::{anyhow, bail, Context, Result};
use needle_scenario::Execution;
use planner_core::chance::ChancePlan;
use planner_core::execute::nominal::check;
use planner_core::execute::risk::{risk_by_obstacle, ObstacleRisk};
use planner_core::execute::schedule::{schedule, Op, Schedule};
use planner_core::wire::DevicePlan;
use planner_core::{Scenario, ScheduledPlan, MAX_OBSTACLES};

/// The device's figures for a plan under the scenario's collision bound, once the prediction
/// made here from its plan gives the same probability and miss, bit for bit, and the same
/// verdict; `None` for a scenario without a bound (and a device that reports none).
pub fn verified_chance(
    scenario: &Scenario,
    execution: &Execution,
    answer: &DevicePlan,
) -> Result<Option<ChancePlan>> {
    let (bound, figures) = match (execution.max_collision_probability, &answer.chance) {
        (None, None) => return Ok(None),
        (Some(_), None) => bail!("the device planned without the collision bound it was given"),
        (None, Some(_)) => bail!("the device reports a collision bound it was not given"),
        (Some(b), Some(f)) => (b, f),
    };
    let risk = match &answer.planned.schedule {
        Some(Ok(s)) => {
            let mut by_obstacle = [ObstacleRisk::default(); MAX_OBSTACLES];
            let model = &execution.model;
            let spread = execution.predicted_as();
            Some(risk_by_obstacle(
                scenario,
                s,
                model,
                spread,
                &mut by_obstacle,
            ))
        }
        _ => None,
    };
    let bits = |v: Option<f32>| v.map(f32::to_bits);
    let here = (
        bits(risk.map(|r| r.collision_probability)),
        bits(risk.map(|r| r.target_error_p95)),
    );
    let there = (
        bits(figures.collision_probability),
        bits(figures.target_error_p95),
    );
    if here != there {
        bail!(
            "the device's predicted collision probability and miss ({:?}, {:?}) differ from \
             those computed here from its plan ({:?}, {:?})",
            figures.collision_probability,
            figures.target_error_p95,
            risk.map(|r| r.collision_probability),
            risk.map(|r| r.target_error_p95)
        );
    }
    let within = risk.is_some_and(|r| r.collision_probability <= bound);
    if within != figures.within_bound {
        bail!("the device's verdict on the bound {bound} differs from the one reached here");
    }
    if figures.margins.len() != scenario.obstacles.len()
        || figures
            .margins
            .iter()
            .any(|m| !(m.is_finite() && *m >= 0.0))
    {
        bail!("the device's obstacle margins are not one finite, non-negative length per obstacle");
    }
    Ok(Some(ChancePlan::from_figures(
        answer.planned.clone(),
        figures,
        risk,
    )))
}

/// The device's schedule of `plan`, once it passes both checks; otherwise why not.
pub fn verified_schedule<'a>(scenario: &Scenario, plan: &'a ScheduledPlan) -> Result<&'a Schedule> {
    let device = plan
        .schedule
        .as_ref()
        .context("the device sent no motor schedule: its report names no best form")?
        .as_ref()
        .map_err(|e| anyhow!("the device sent no motor schedule for its plan: {e}"))?;
    let best = plan
        .report
        .best()
        .context("the device's report names no best form")?;
    let v = check(scenario, device);
    if !v.feasible {
        bail!(
            "the device's motor schedule fails the nominal re-check: executed, it ends {:.4} mm \
             from the target (tolerance {}), passes {:.3} mm from the nearest obstacle (at least \
             {} needed) and {} the twist limit of {} deg",
            v.target_error,
            scenario.target.tolerance,
            v.min_clearance,
            scenario.options.min_clearance,
            if v.within_twist { "keeps" } else { "breaks" },
            scenario.driver.max_twist_deg
        );
    }
    let host = schedule(scenario, best)
        .map_err(|e| anyhow!("no motor schedule can be made here from the device's plan: {e}"))?;
    if let Some(diff) = first_difference(&host, device) {
        bail!(
            "the device's motor schedule differs from the one computed here from its plan: {diff}"
        );
    }
    Ok(device)
}

/// Every number of a schedule with its name, as bits (so -0 and 0, or two NaNs, differ too).
fn words(s: &Schedule) -> Vec<(String, u32)> {
    let p = &s.posture;
    let mut w = Vec::new();
    for (name, v) in [("entry", p.entry), ("direction", p.direction)] {
        for (i, c) in v.iter().enumerate() {
            w.push((format!("posture.{name}[{i}]"), c.to_bits()));
        }
    }
    w.push(("posture.theta1_deg".into(), p.theta1_deg.to_bits()));
    w.push(("posture.theta2_deg".into(), p.theta2_deg.to_bits()));
    w.push(("posture.roll_deg".into(), p.roll_deg.to_bits()));
    w.push(("number of steps".into(), s.steps.len() as u32));
    for (i, st) in s.steps.iter().enumerate() {
        let n = i + 1;
        let (tag, value, turns) = match st.op {
            Op::Rotate { angle_deg } => (0, angle_deg, 0),
            Op::Insert { length_mm } => (1, length_mm, 0),
            Op::InsertSpin { length_mm, turns } => (2, length_mm, turns),
            // A plan's schedule has none; compared all the same, the duty's bits as the turns.
            Op::InsertDuty { length_mm, duty } => (3, length_mm, duty.to_bits()),
        };
        w.push((format!("step {n} op"), tag));
        w.push((format!("step {n} angle or length"), value.to_bits()));
        w.push((format!("step {n} turns"), turns));
        w.push((format!("step {n} duration_s"), st.duration_s.to_bits()));
    }
    w.push(("duration_s".into(), s.duration_s.to_bits()));
    w.push(("max_twist_deg".into(), s.max_twist_deg.to_bits()));
    w
}

/// The first number in which `device` differs from `host`, described; `None` when equal.
fn first_difference(host: &Schedule, device: &Schedule) -> Option<String> {
    if host.steps.len() != device.steps.len() {
        return Some(format!(
            "{} steps from the device, {} here",
            device.steps.len(),
            host.steps.len()
        ));
    }
    let (h, d) = (words(host), words(device));
    h.iter().zip(&d).find(|(a, b)| a.1 != b.1).map(|(a, b)| {
        let show = |bits: u32| f32::from_bits(bits);
        format!(
            "{} is {:?} (bits {:#010x}) from the device, {:?} (bits {:#010x}) here",
            a.0,
            show(b.1),
            b.1,
            show(a.1),
            a.1
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner_core::plan_scheduled;

    fn paper() -> (Scenario, ScheduledPlan) {
        let s = Scenario::paper();
        let p = plan_scheduled(&s).unwrap();
        (s, p)
    }

    #[test]
    fn the_devices_own_schedule_passes() {
        let (s, p) = paper();
        assert_eq!(
            verified_schedule(&s, &p).unwrap(),
            p.schedule.as_ref().unwrap().as_ref().unwrap()
        );
    }

    #[test]
    fn a_schedule_that_misses_the_target_is_refused() {
        let (s, mut p) = paper();
        let sched = p.schedule.as_mut().unwrap().as_mut().unwrap();
        if let Op::Insert { length_mm } = &mut sched.steps[0].op {
            *length_mm += 1.0;
        }
        let e = verified_schedule(&s, &p).unwrap_err().to_string();
        assert!(e.contains("fails the nominal re-check"), "{e}");
        assert!(e.contains("from the target"), "{e}");
    }

    #[test]
    fn a_schedule_one_bit_off_is_refused_by_name() {
        let (s, mut p) = paper();
        let sched = p.schedule.as_mut().unwrap().as_mut().unwrap();
        sched.duration_s = f32::from_bits(sched.duration_s.to_bits() + 1);
        let e = verified_schedule(&s, &p).unwrap_err().to_string();
        assert!(e.contains("differs") && e.contains("duration_s"), "{e}");
    }

    #[test]
    fn a_missing_schedule_is_refused() {
        let (s, mut p) = paper();
        p.schedule = Some(Err(planner_core::execute::schedule::ScheduleError::NoPath));
        let e = verified_schedule(&s, &p).unwrap_err().to_string();
        assert!(e.contains("no motor schedule"), "{e}");
        p.schedule = None;
        let e = verified_schedule(&s, &p).unwrap_err().to_string();
        assert!(e.contains("no motor schedule"), "{e}");
    }
}
