//! The broad phase changes the work, never the answer: over a seeded family of random scenarios
//! (64 to 512 spheres) and paths, the check's clearances, the steering's prediction and the
//! collision-risk spread measured with culling equal, bit for bit, those measured over every
//! sphere.

use crate::check::{clearances, clearances_of, rebuild};
use crate::execute::perturbation::Perturbation;
use crate::execute::risk::{risk_culled, Culling, Execution, ExecutionRisk, ObstacleRisk};
use crate::execute::schedule::{continuation_steps, Posture, Schedule};
use crate::model::broad::{Broad, Set};
use crate::model::form::{Form, SegmentKind};
use crate::model::scenario::{Obstacle, Scenario, Workspace, MAX_OBSTACLES};
use crate::report::{Insertion, SegmentPlan, Segments};
use crate::steer::replan::{predict_with, Prediction};
use crate::steer::SteerConfig;

/// A deterministic stream of numbers in [0, 1) (a linear congruential generator).
struct Draw(u32);

impl Draw {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (self.0 >> 8) as f32 / (1u32 << 24) as f32
    }

    fn between(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
}

const WORDS: [&str; 8] = ["L", "RL", "LRL", "RRL", "RLR", "RRR", "R", "RR"];

/// Case `case`: spheres scattered around the entry's axis, a risk reach or none, and a path of
/// a random form, posture, lengths and bevels (often through spheres).
fn case(case: u32) -> (Scenario, Form, Insertion, Segments) {
    let mut d = Draw(case.wrapping_mul(2_654_435_761).wrapping_add(17));
    let mut s = Scenario::paper();
    s.options.workspace = if case % 7 == 3 {
        Workspace::PlaneYz
    } else {
        Workspace::Space
    };
    s.options.risk_within_mm = match case % 4 {
        0 => None,
        1 => Some(2.0),
        2 => Some(5.0),
        _ => Some(20.0),
    };
    let count = 64 + (d.next() * 449.0) as usize;
    s.obstacles.clear();
    for _ in 0..count.min(MAX_OBSTACLES) {
        let center = [
            d.between(-70.0, 70.0),
            d.between(-70.0, 70.0),
            d.between(-20.0, 160.0),
        ];
        let radius = d.between(0.5, 9.0);
        let _ = s.obstacles.push(Obstacle { center, radius });
    }
    let form = Form::parse(WORDS[(d.next() * 8.0) as usize % 8]).unwrap();
    let insertion = Insertion {
        theta1_deg: d.between(-20.0, 20.0),
        theta2_deg: d.between(-20.0, 20.0),
        ..Insertion::default()
    };
    let mut segments = Segments::new();
    for i in 0..form.len() {
        let _ = segments.push(SegmentPlan {
            kind: form.kind(i),
            length: d.between(2.0, 60.0),
            bevel_deg: d.between(-180.0, 180.0),
        });
    }
    (s, form, insertion, segments)
}

fn bits_of_risk(r: &ExecutionRisk) -> [u32; 14] {
    let e = &r.end;
    let mut out = [0u32; 14];
    out[0] = r.collision_probability.to_bits();
    out[1] = r.target_error_p95.to_bits();
    for k in 0..3 {
        out[2 + k] = e.mean[k].to_bits();
        out[5 + k] = e.covariance[(k, k)].to_bits();
    }
    out[8] = e.covariance[(0, 1)].to_bits();
    out[9] = e.covariance[(1, 2)].to_bits();
    out[10] = e.covariance[(0, 2)].to_bits();
    out[11] = e.depth.to_bits();
    out
}

fn bits_of_share(o: &ObstacleRisk) -> [u32; 4] {
    [o.probability, o.clearance, o.sd, o.steering_margin].map(f32::to_bits)
}

fn bits_of_prediction(p: &Prediction) -> [u32; 5] {
    [
        p.target_error.to_bits(),
        p.min_clearance.to_bits(),
        p.end.p.x.to_bits(),
        p.end.p.y.to_bits(),
        p.end.p.z.to_bits(),
    ]
}

/// The path's motor steps from the posture.
fn schedule_of(s: &Scenario, insertion: &Insertion, segments: &Segments) -> Option<Schedule> {
    let (steps, peak) = continuation_steps(&s.driver, segments, 0.0, s.arc_duty()).ok()?;
    let first = segments.first()?;
    Some(Schedule {
        posture: Posture {
            entry: s.entry.position,
            theta1_deg: insertion.theta1_deg,
            theta2_deg: insertion.theta2_deg,
            direction: s.entry.direction,
            roll_deg: first.bevel_deg,
        },
        steps,
        duration_s: 0.0,
        max_twist_deg: peak,
    })
}

#[test]
fn the_check_and_the_prediction_measure_the_same_culled_as_over_every_sphere() {
    let mut through = 0;
    for n in 0..200 {
        let (s, form, insertion, segments) = case(n);
        let geo = rebuild(&s, form, &insertion, &segments);
        let every = clearances_of(&s, &geo, &Set::all(s.obstacles.len()));
        let culled = clearances(&s, &geo);
        assert_eq!(
            (culled.0.to_bits(), culled.1.to_bits()),
            (every.0.to_bits(), every.1.to_bits()),
            "case {n}: {culled:?} against {every:?}"
        );
        through += usize::from(every.0 < 0.0);
        let Ok((steps, _)) = continuation_steps(&s.driver, &segments, 0.0, s.arc_duty()) else {
            continue;
        };
        let broad = Broad::new(&s.obstacles);
        let (tip, radius) = (geo.starts[0], geo.radius);
        let end = geo.end();
        let near = predict_with(&s, Some(&broad), &tip, &steps, radius, end);
        let all = predict_with(&s, None, &tip, &steps, radius, end);
        assert_eq!(
            bits_of_prediction(&near),
            bits_of_prediction(&all),
            "case {n}"
        );
    }
    // Paths through spheres and paths clear of them both occur.
    assert!(through > 20 && through < 180, "{through}");
}

#[test]
fn the_risk_spread_is_the_same_culled_as_over_every_sphere() {
    let steered = Execution::Steered(SteerConfig::DEFAULT.noise);
    let mut by_culled = [ObstacleRisk::default(); MAX_OBSTACLES];
    let mut by_every = [ObstacleRisk::default(); MAX_OBSTACLES];
    let mut risky = 0;
    for n in 0..200 {
        let (s, _, insertion, segments) = case(n);
        let Some(schedule) = schedule_of(&s, &insertion, &segments) else {
            continue;
        };
        let p = match n % 3 {
            0 => Perturbation::default(),
            1 => Perturbation::none(),
            _ => Perturbation {
                curvature_spread: 0.005,
                insertion_error_mm: 0.05,
                ..Perturbation::default()
            },
        };
        let execution = if n % 5 == 4 {
            steered
        } else {
            Execution::OpenLoop
        };
        let every = risk_culled(&s, &schedule, &p, execution, &mut by_every, Culling::None);
        for how in [Culling::AsWalked, Culling::Kept] {
            let culled = risk_culled(&s, &schedule, &p, execution, &mut by_culled, how);
            assert_eq!(
                bits_of_risk(&culled),
                bits_of_risk(&every),
                "case {n} {how:?}"
            );
            for (o, (a, b)) in by_culled.iter().zip(&by_every).enumerate() {
                assert_eq!(
                    bits_of_share(a),
                    bits_of_share(b),
                    "case {n} {how:?} sphere {o}"
                );
            }
        }
        risky +=
            usize::from(every.collision_probability > 0.0 && every.collision_probability < 1.0);
    }
    assert!(risky > 20, "{risky}");
}

/// A bug in the tree must not hide a collision: an arc through one of 256 spheres is refused by
/// the check, which uses its tree there (many spheres, a risk reach, an arc).
#[test]
fn a_path_through_a_sphere_is_refused_with_the_tree_in_use() {
    let (mut s, ..) = case(1);
    s.obstacles.truncate(255);
    s.options.workspace = Workspace::Space;
    s.options.risk_within_mm = Some(5.0);
    let arc = [SegmentPlan {
        kind: SegmentKind::Arc,
        length: 60.0,
        bevel_deg: 30.0,
    }];
    let form = Form::parse("R").unwrap();
    let geo = rebuild(&s, form, &Insertion::default(), &arc);
    let on = geo.starts[0].point_at(SegmentKind::Arc, 40.0, geo.radius);
    // Clear the arc, then put one sphere on it.
    let near = |o: &Obstacle| {
        let c = on - crate::model::kinematics::V3::new(o.center[0], o.center[1], o.center[2]);
        c.norm() < 80.0
    };
    s.obstacles.retain(|o| !near(o));
    let _ = s.obstacles.push(Obstacle {
        center: [on.x, on.y, on.z],
        radius: 3.0,
    });
    assert!(s.obstacles.len() > 32, "{}", s.obstacles.len());
    let verdict = crate::check::check(&s, form, &Insertion::default(), &arc);
    assert!(!verdict.feasible, "{verdict:?}");
    assert!((verdict.min_clearance + 3.0).abs() < 1e-3, "{verdict:?}");
    assert!(verdict.risk.is_infinite());
}
