//! The steering controller: each stop reason, each tracker fault, idempotent sequence numbers,
//! and (property test) random readings never panic it nor make it command a continuation whose
//! nominal execution enters an obstacle.

use planner_core::execute::nominal::{execute_from, posture_frame};
use planner_core::execute::schedule::{schedule, Op, Schedule, Step};
use planner_core::model::clearance::closest;
use planner_core::model::kinematics::{Frame, V3};
use planner_core::model::scenario::{Obstacle, Workspace};
use planner_core::steer::{
    Command, Pose, Reading, SteerConfig, SteerReply, Steering, StopReason, TipMeasurement,
};
use planner_core::{plan, Scenario, SegmentKind};
use proptest::prelude::*;

fn space() -> Scenario {
    let mut s = Scenario::paper();
    s.options.workspace = Workspace::Space;
    s.target.position = [12.0, 8.0, 85.0];
    s.obstacles.clear();
    for (c, r) in [([6.0, 4.0, 42.0], 9.0), ([-10.0, 14.0, 58.0], 8.0)] {
        s.obstacles
            .push(Obstacle {
                center: c,
                radius: r,
            })
            .unwrap();
    }
    s
}

fn planned(s: &Scenario) -> Schedule {
    let best = plan(s).unwrap().best().unwrap().clone();
    schedule(s, &best).unwrap()
}

fn arr(v: V3) -> [f32; 3] {
    [v.x, v.y, v.z]
}

/// Drives the controller with exact readings of the nominal needle (no tissue error), every mm.
struct Bench {
    s: Scenario,
    steering: Steering,
    tip: Frame,
    steps: Vec<Step>,
    depth: f32,
    base: f32,
    seq: u32,
}

impl Bench {
    fn new(s: Scenario) -> Bench {
        let sched = planned(&s);
        let steering = Steering::start(&s, &sched, &SteerConfig::DEFAULT).unwrap();
        Bench {
            tip: posture_frame(&s, &sched),
            steps: sched.steps.to_vec(),
            s,
            steering,
            depth: 0.0,
            base: 0.0,
            seq: 0,
        }
    }

    fn reading(&mut self, pose: bool) -> TipMeasurement {
        self.seq += 1;
        TipMeasurement {
            seq: self.seq,
            depth_mm: self.depth,
            base_deg: self.base,
            pose: pose.then(|| Pose {
                position: arr(self.tip.p),
                heading: arr(self.tip.e3()),
                bevel: Some(arr(self.tip.e2())),
            }),
            target: Some(self.s.target.position),
        }
    }

    /// Executes the steps, `fix(depth)` saying whether the tracker sees the tip there; returns
    /// the last reply and every reply that replaced the steps.
    fn run(&mut self, fix: impl Fn(f32) -> bool) -> (SteerReply, Vec<SteerReply>) {
        let radius = self.s.needle.curvature_radius;
        let mut replaced = Vec::new();
        'steps: loop {
            let steps = self.steps.clone();
            for step in &steps {
                let (pieces, radius) = match step.op.segment(radius) {
                    None => {
                        if let Op::Rotate { angle_deg } = step.op {
                            self.base += angle_deg;
                            self.tip = self.tip.rolled(angle_deg.to_radians());
                        }
                        (vec![], radius)
                    }
                    Some((kind, length, r)) => (pieces(kind, length), r),
                };
                let mut replies = Vec::new();
                if pieces.is_empty() {
                    let m = self.reading(fix(self.depth));
                    replies.push(self.steering.update(&m));
                }
                for (kind, len) in pieces {
                    self.tip = self.tip.advanced(kind, len, radius);
                    self.depth += len;
                    let m = self.reading(fix(self.depth));
                    let r = self.steering.update(&m);
                    let act = !matches!(r.command, Command::Continue);
                    replies.push(r);
                    if act {
                        break;
                    }
                }
                let last = replies.pop().unwrap();
                match &last.command {
                    Command::Continue => {}
                    Command::Replace(s) => {
                        self.steps = s.to_vec();
                        replaced.push(last.clone());
                        continue 'steps;
                    }
                    Command::Stop(_) => return (last, replaced),
                }
            }
            panic!("the steps ran out without a stop");
        }
    }
}

fn pieces(kind: SegmentKind, length: f32) -> Vec<(SegmentKind, f32)> {
    let n = length.ceil().max(1.0) as usize;
    vec![(kind, length / n as f32); n]
}

#[test]
fn exact_readings_steer_the_plan_to_the_target() {
    for s in [Scenario::paper(), space()] {
        let mut b = Bench::new(s.clone());
        let (last, _) = b.run(|_| true);
        assert_eq!(last.command, Command::Stop(StopReason::TargetReached));
        let t = s.target.position;
        let miss = (b.tip.p - V3::new(t[0], t[1], t[2])).norm();
        assert!(miss <= s.target.tolerance, "ends {miss} mm from the target");
        let stats = b.steering.stats();
        assert_eq!(stats.outliers, 0);
        assert_eq!(stats.replan_failures, 0);
    }
}

/// The pose a device reports of its estimate gives back the tip frame it came from (a viewer
/// draws the continuation from it), along a 3-D insertion that rolls the bevel.
#[test]
fn a_reported_pose_gives_back_the_tip_frame() {
    let s = space();
    let mut frames = 0;
    let mut tip = posture_frame(&s, &planned(&s));
    for (kind, length) in pieces(SegmentKind::Arc, 30.0) {
        tip = tip.advanced(kind, length, 63.7).rolled(0.7);
        let back = Pose::of_frame(&tip).frame().expect("a bevel");
        assert!((back.p - tip.p).norm() < 1e-6);
        assert!(
            (back.r - tip.r).norm() < 1e-5,
            "{:?} vs {:?}",
            back.r,
            tip.r
        );
        frames += 1;
    }
    assert!(frames > 10);
    let no_bevel = Pose {
        bevel: None,
        ..Pose::of_frame(&tip)
    };
    assert_eq!(no_bevel.frame(), None);
}

#[test]
fn a_schedule_that_ends_short_is_missed_not_reached() {
    // The controller never replans for the target error here: the run ends where the schedule
    // does, `cut` mm of the last insertion short.
    let config = SteerConfig {
        replan_error_mm: 1000.0,
        ..SteerConfig::DEFAULT
    };
    for (cut, expect) in [
        (0.0, StopReason::TargetReached),
        (0.5, StopReason::TargetReached),
        (4.0, StopReason::Missed),
    ] {
        let s = Scenario::paper();
        let mut sched = planned(&s);
        let last = sched.steps.len() - 1;
        match &mut sched.steps[last].op {
            Op::Insert { length_mm } | Op::InsertSpin { length_mm, .. } => *length_mm -= cut,
            _ => panic!("a plan's schedule ends with an insertion"),
        }
        let mut b = Bench::new(s.clone());
        b.steering = Steering::start(&s, &sched, &config).unwrap();
        b.steps = sched.steps.to_vec();
        let (last, replaced) = b.run(|_| true);
        assert!(replaced.is_empty(), "cut {cut}: replanned");
        assert_eq!(last.command, Command::Stop(expect), "cut {cut}: {last:?}");
        let miss = last.predicted_error_mm;
        assert!((miss - cut).abs() < 0.3, "cut {cut}: predicted miss {miss}");
    }
}

#[test]
fn a_short_dropout_is_bridged_and_a_long_one_stops_with_tracking_lost() {
    let mut b = Bench::new(space());
    let (last, _) = b.run(|d| !(20.0..27.0).contains(&d));
    assert_eq!(last.command, Command::Stop(StopReason::TargetReached));
    assert!(b.steering.stats().no_fix >= 6);

    let mut b = Bench::new(space());
    let gap = SteerConfig::DEFAULT.max_gap_mm;
    let (last, _) = b.run(|d| !(20.0..20.0 + 2.0 * gap).contains(&d));
    assert_eq!(last.command, Command::Stop(StopReason::TrackingLost));
    assert!(
        b.depth > 20.0 + gap && b.depth < 20.0 + gap + 1.5,
        "stopped at {}",
        b.depth
    );
}

#[test]
fn an_outlier_is_rejected_and_counted() {
    let mut b = Bench::new(space());
    b.depth = 1.0;
    b.tip = b.tip.advanced(SegmentKind::Arc, 1.0, 63.7);
    let mut m = b.reading(true);
    if let Some(p) = m.pose.as_mut() {
        p.position[0] += 30.0;
    }
    let r = b.steering.update(&m);
    assert_eq!(r.reading, Reading::Outlier);
    assert_eq!(b.steering.stats().outliers, 1);
    // Only the prediction moved the estimate: 1 mm along the arc, where the tip is.
    let off = (b.steering.estimate().tip.p - b.tip.p).norm();
    assert!(off < 1e-3, "{off}");
}

#[test]
fn a_repeated_reading_is_answered_again_and_an_old_one_ignored() {
    let mut b = Bench::new(space());
    b.depth = 1.0;
    b.tip = b.tip.advanced(SegmentKind::Arc, 1.0, 63.7);
    let m = b.reading(true);
    let first = b.steering.update(&m);
    let estimate = b.steering.estimate().tip;
    let again = b.steering.update(&m);
    assert_eq!(again.reading, Reading::Repeated);
    assert_eq!(again.command, first.command);
    assert_eq!(
        b.steering.estimate().tip,
        estimate,
        "a repeat is not applied twice"
    );
    let mut old = m;
    old.seq -= 1;
    assert_eq!(b.steering.update(&old).reading, Reading::Stale);
    assert_eq!(b.steering.stats().stale, 1);
    assert_eq!(b.steering.stats().repeated, 1);
    assert_eq!(b.steering.stats().readings, 1);
}

#[test]
fn progress_that_is_not_a_number_or_goes_back_stops_with_bad_measurement() {
    for depth in [f32::NAN, -5.0] {
        let mut b = Bench::new(space());
        b.depth = 2.0;
        let m = b.reading(true);
        let _ = b.steering.update(&m);
        b.depth = depth;
        let m = b.reading(true);
        let r = b.steering.update(&m);
        assert_eq!(r.command, Command::Stop(StopReason::BadMeasurement));
        // It stays stopped.
        b.depth = 3.0;
        let m = b.reading(true);
        let r = b.steering.update(&m);
        assert_eq!(r.command, Command::Stop(StopReason::BadMeasurement));
    }
}

#[test]
fn a_tip_headed_into_an_obstacle_stops_with_no_safe_continuation() {
    let mut s = space();
    // An obstacle just ahead of where the tip is measured, filling the way to the target.
    let mut b = Bench::new(s.clone());
    b.depth = 1.0;
    let tip = b.tip.advanced(SegmentKind::Arc, 1.0, 63.7);
    let ahead = tip.p + tip.e3() * 6.0;
    s.obstacles.clear();
    s.obstacles
        .push(Obstacle {
            center: arr(ahead),
            radius: 5.5,
        })
        .unwrap();
    let sched = planned(&space());
    let mut steering = Steering::start(&s, &sched, &SteerConfig::DEFAULT).unwrap();
    let m = TipMeasurement::fix(1, 1.0, 0.0, arr(tip.p), arr(tip.e3()), arr(tip.e2()));
    let r = steering.update(&m);
    assert_eq!(r.command, Command::Stop(StopReason::NoSafeContinuation));
    assert!(r.predicted_clearance_mm <= 0.0);
}

/// The smallest clearance of `steps` executed from `tip` (exact, spheres).
fn clearance_of(s: &Scenario, tip: &Frame, steps: &[Step], radius: f32) -> f32 {
    let mut least = f32::INFINITY;
    execute_from(*tip, steps, radius, |start, kind, len, radius| {
        for o in &s.obstacles {
            let c = V3::new(o.center[0], o.center[1], o.center[2]);
            least = least.min(closest(start, kind, len, radius, &c).distance - o.radius);
        }
    });
    least
}

fn number() -> impl Strategy<Value = f32> {
    prop_oneof![
        6 => -80.0f32..120.0,
        1 => prop::sample::select(vec![f32::NAN, f32::INFINITY, -f32::INFINITY, 1e30, 0.0]),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(20261201),
        ..ProptestConfig::default()
    })]

    /// Random readings (garbage among them) never panic the controller, and every continuation
    /// it commands, executed from its estimate, keeps clear of every obstacle.
    #[test]
    fn random_readings_never_command_a_collision(
        readings in prop::collection::vec(
            (0u32..3, 0.0f32..3.0, -30.0f32..30.0, [number(), number(), number()],
             [number(), number(), number()], any::<bool>()),
            1..40,
        ),
    ) {
        let s = space();
        let sched = planned(&s);
        let mut steering = Steering::start(&s, &sched, &SteerConfig::DEFAULT).unwrap();
        let (mut seq, mut depth, mut base) = (0u32, 0.0f32, 0.0f32);
        for (dseq, push, turn, position, heading, fix) in readings {
            seq = seq.wrapping_add(dseq);
            depth += push;
            base += turn;
            let m = TipMeasurement {
                seq,
                depth_mm: depth,
                base_deg: base,
                pose: fix.then_some(Pose { position, heading, bevel: Some([1.0, 0.0, 0.0]) }),
                target: None,
            };
            let r = steering.update(&m);
            if let Command::Replace(steps) = &r.command {
                let e = steering.estimate();
                let radius = s.needle.curvature_radius / e.factor;
                let clear = clearance_of(&s, &e.tip, steps, radius);
                prop_assert!(clear > s.options.min_clearance, "commanded {clear} mm: {steps:?}");
            }
        }
    }
}
