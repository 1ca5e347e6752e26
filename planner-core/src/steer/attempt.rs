//! One solve of a continuation from the tip: the SQP from a start, and, when the start lies
//! inside the margin (the tip drifted towards an obstacle), a clearing solve before it.

use super::continuation::{wrapped_deg, ReplanInput, Replanned};
use crate::model::form::Form;
use crate::model::scenario::Scenario;
use crate::optim::problem::{Problem, Vars, MAX_VARS};
use crate::optim::sqp::{solve_within, SolveFailure};
use crate::report::{SegmentPlan, Segments};

/// Solves `form` from the tip, from `start` (lengths in mm, bevels in degrees before each arc).
/// `sub` is changed during a clearing solve and put back as it was.
pub(super) fn attempt(
    input: &ReplanInput,
    sub: &mut Scenario,
    form: Form,
    start: &[SegmentPlan],
    spent: &mut (u32, u32),
) -> Option<Replanned> {
    let x0 = {
        let p = Problem::continuation(sub, form, input.tip);
        let x0 = start_vars(&p, start);
        match solved(&p, &x0, input.iterations, spent) {
            Ok(sol) => {
                let exact = solution_segments(&p, &sol)?;
                return super::turns::commanded(input, &exact, spent);
            }
            Err(SolveFailure::StartInadmissible) => x0,
            Err(_) => return None,
        }
    };
    let exact = cleared_first(input, sub, form, &x0, spent)?;
    super::turns::commanded(input, &exact, spent)
}

/// The solver's variables for the segments `start` of `p`'s form.
fn start_vars(p: &Problem, start: &[SegmentPlan]) -> Vars {
    let mut x0: Vars = [0.0; MAX_VARS];
    for (i, seg) in start.iter().enumerate().take(p.form.len()) {
        let k = p.length_var(i);
        x0[k] = crate::fmath::clamp(seg.length / p.radius, p.lower[k], p.upper[k]);
        if let Some(b) = p.bevel_var(i) {
            x0[b] = seg.bevel_deg.to_radians();
        }
    }
    x0
}

/// How much more the obstacles weigh while a path inside the margin is moved out of it.
const CLEARING_RISK_WEIGHT: f32 = 20.0;

/// From a start inside the margin (the tip has drifted towards an obstacle), where the
/// feasible-path SQP cannot begin: the same problem solved first with the scenario's own floor
/// and the obstacles weighing [`CLEARING_RISK_WEIGHT`] times more, which moves the path away
/// from them, then again with the margin from there.
fn cleared_first(
    input: &ReplanInput,
    sub: &mut Scenario,
    form: Form,
    x0: &Vars,
    spent: &mut (u32, u32),
) -> Option<Segments> {
    // Relaxed in place and put back: a copy of the scenario would take 16 bytes a sphere of the
    // device's stack.
    let (floor, risk) = (sub.options.min_clearance, sub.weights.risk);
    sub.options.min_clearance -= input.margin;
    sub.weights.risk *= CLEARING_RISK_WEIGHT;
    let away = solved(
        &Problem::continuation(sub, form, input.tip),
        x0,
        input.iterations,
        spent,
    );
    sub.options.min_clearance = floor;
    sub.weights.risk = risk;
    let away = away.ok()?;
    let p = Problem::continuation(sub, form, input.tip);
    let sol = solved(&p, &away, input.iterations, spent).ok()?;
    solution_segments(&p, &sol)
}

/// The SQP's solution from `x0`, its cost counted in `spent`.
fn solved(
    p: &Problem,
    x0: &Vars,
    iterations: u32,
    spent: &mut (u32, u32),
) -> Result<Vars, SolveFailure> {
    match solve_within(p, x0, iterations) {
        Ok(sol) => {
            spent.0 += sol.evaluations;
            spent.1 += sol.iterations;
            Ok(sol.eval.x)
        }
        Err(e) => {
            spent.0 += 1;
            Err(e)
        }
    }
}

/// The segments of the solution `x` (bevels in degrees, wrapped).
fn solution_segments(p: &Problem, x: &Vars) -> Option<Segments> {
    let lengths = p.lengths(x);
    let bevels = p.bevels(x);
    let mut out = Segments::new();
    for i in 0..p.form.len() {
        out.push(SegmentPlan {
            kind: p.form.kind(i),
            length: lengths[i],
            bevel_deg: wrapped_deg(bevels[i]),
        })
        .ok()?;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::form::SegmentKind;
    use crate::model::kinematics::{Frame, V3};
    use crate::model::scenario::{Obstacle, Workspace};
    use crate::steer::continuation::{form_of, sub_scenario};

    /// A continuation (R L R: two degrees of freedom beyond reaching the target) that now
    /// passes a sphere inside the margin: the SQP cannot start from it, the clearing moves it
    /// out first, and the replan keeps the margin and reaches the target.
    #[test]
    fn a_start_inside_the_margin_is_cleared_first() {
        let mut scenario = Scenario::paper();
        scenario.options.workspace = Workspace::Space;
        scenario.obstacles.clear();
        let r = scenario.needle.curvature_radius;
        let tip = Frame {
            p: V3::zeros(),
            r: nalgebra::Matrix3::identity(),
        };
        let mut remaining = Segments::new();
        for (kind, length, bevel_deg) in [
            (SegmentKind::Arc, 30.0, 0.0),
            (SegmentKind::Line, 40.0, 0.0),
            (SegmentKind::Arc, 20.0, 90.0),
        ] {
            remaining
                .push(SegmentPlan {
                    kind,
                    length,
                    bevel_deg,
                })
                .unwrap();
        }
        let bend_end = tip.advanced(SegmentKind::Arc, 30.0, r);
        let end = bend_end
            .advanced(SegmentKind::Line, 40.0, r)
            .rolled(90f32.to_radians())
            .advanced(SegmentKind::Arc, 20.0, r);
        // A sphere beside the middle of the line, 0.15 mm from it, across the bend's plane.
        let middle = bend_end.advanced(SegmentKind::Line, 20.0, r).p;
        let across = bend_end.e3().cross(&bend_end.e2()).normalize();
        let centre = middle + across * 5.15;
        let _ = scenario.obstacles.push(Obstacle {
            center: [centre.x, centre.y, centre.z],
            radius: 5.0,
        });
        let input = ReplanInput {
            scenario: &scenario,
            tip,
            target: end.p,
            radius: r,
            twist_deg: 0.0,
            iterations: 10,
            margin: 0.4,
            inserted_mm: 0.0,
            dead_band_deg: 0.0,
            arc_duty: 1.0,
            spend_reserve: true,
            turn_early: false,
        };
        let mut sub = sub_scenario(&input);
        let form = form_of(&remaining).unwrap();
        let p = Problem::continuation(&sub, form, tip);
        let mut spent = (0, 0);
        let x0 = start_vars(&p, &remaining);
        assert_eq!(
            solved(&p, &x0, 10, &mut spent).err(),
            Some(SolveFailure::StartInadmissible)
        );
        let found =
            attempt(&input, &mut sub, form, &remaining, &mut spent).expect("a continuation");
        assert!(
            found.prediction.min_clearance > 0.4,
            "{:?}",
            found.prediction
        );
        assert!(found.prediction.target_error <= scenario.target.tolerance);
    }
}
