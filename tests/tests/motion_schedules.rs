//! The motion core on the planner's schedules, seeded and deterministic: thousands of schedules
//! (continuations drawn over random drivers, axes and segments, and the plans of the generated
//! scenario families) become step trains that never pass a speed, acceleration or soft limit
//! (checked step by step by `needle_motion::check`, independent of how the train was made), whose
//! executed displacement equals the commanded one to a step, whose coordinated spins keep their
//! ratio, and which are the same twice.
//!
//! ```text
//! cargo test -p needle-e2e --profile ci --test motion_schedules -- --nocapture
//! ```

use needle_e2e::reference::random::random_scenario;
use needle_motion::check::TrainCheck;
use needle_motion::moves::Planned;
use needle_motion::runner::SegmentRun;
use needle_motion::{Axis, Controller, Inputs, MotionConfig, Move, SafetyConfig, State};
use needle_sim::random::{seeded, Draw};
use planner_core::execute::schedule::{continuation_steps, schedule, Op, Step};
use planner_core::model::scenario::Driver;
use planner_core::wire::motion_rates;
use planner_core::{plan, Scenario, SegmentKind, SegmentPlan};

/// Schedules drawn as continuations.
const DRAWN: u64 = 2000;
/// Scenarios of the generated families planned (each in the plane and in space).
const PLANNED: u64 = 12;

fn to_move(op: &Op) -> Move {
    match *op {
        Op::Rotate { angle_deg } => Move::Rotate { angle_deg },
        Op::Insert { length_mm } => Move::Insert { length_mm },
        Op::InsertSpin { length_mm, turns } => Move::InsertSpin { length_mm, turns },
        Op::InsertDuty { length_mm, duty } => Move::InsertDuty { length_mm, duty },
    }
}

/// Axes drawn over common driver hardware: lead screws of 1 to 5 mm with 200 to 3200 steps a
/// turn, shaft motors of 200 to 3200 steps a turn, timers of 0.25 to 2 MHz.
fn drawn_config(seed: u64, needle_mm: f32, d: &Driver) -> MotionConfig {
    let mut rng = seeded(seed ^ 0x6d6f_7469_6f6e);
    let mut cfg = MotionConfig::bench(needle_mm, d.max_twist_deg, motion_rates(d));
    cfg.tick_hz = [250_000, 1_000_000, 2_000_000][rng.int(0, 2)];
    let micro = [200.0, 400.0, 800.0, 1600.0, 3200.0];
    cfg.axes[0].steps_per_unit = micro[rng.int(0, 4)] / rng.range(1.0, 5.0) as f32;
    cfg.axes[1].steps_per_unit = micro[rng.int(0, 4)] / 360.0;
    // Room for the step interrupt: at least `MIN_STEP_TICKS` (8) ticks a step at top speed.
    let f = cfg.tick_hz as f32 / 8.1;
    for (i, (v, a)) in [
        ((2.0, 20.0), (20.0, 400.0)),
        ((360.0, 3600.0), (3600.0, 72_000.0)),
    ]
    .into_iter()
    .enumerate()
    {
        let spu = cfg.axes[i].steps_per_unit;
        cfg.axes[i].max_speed = (rng.range(v.0, v.1) as f32).min(f / spu);
        cfg.axes[i].max_accel = rng.range(a.0, a.1) as f32;
    }
    assert_eq!(cfg.validate(), Ok(()), "seed {seed}");
    cfg
}

/// A driver within `Driver::validate`'s ranges, around common needle drivers.
fn drawn_driver(rng: &mut impl Draw) -> Driver {
    Driver {
        insert_speed: rng.range(0.5, 5.0) as f32,
        rotate_speed: rng.range(60.0, 720.0) as f32,
        spin_rate: rng.range(1.0, 8.0) as f32,
        max_twist_deg: rng.range(360.0, 1080.0) as f32,
    }
}

/// A continuation of one to four segments from the entry: the steps the planner gives a plan's
/// segments (a rotation where the bevel turns, arcs pushed or duty-cycled, lines spun).
fn drawn_schedule(seed: u64) -> (Driver, Vec<Step>) {
    let mut rng = seeded(seed);
    let d = drawn_driver(&mut rng);
    let mut segments = Vec::new();
    for _ in 0..rng.int(1, 4) {
        let kind = if rng.unit() < 0.5 {
            SegmentKind::Arc
        } else {
            SegmentKind::Line
        };
        segments.push(SegmentPlan {
            kind,
            length: rng.range(0.05, 25.0) as f32,
            bevel_deg: rng.range(-179.9, 180.0) as f32,
        });
    }
    let duty = if rng.unit() < 0.5 {
        1.0
    } else {
        rng.range(0.5, 1.0) as f32
    };
    let (steps, _) = continuation_steps(&d, &segments, 0.0, duty).expect("a valid continuation");
    (d, steps.to_vec())
}

/// What a run of a schedule gives: the event train's hash, where it ended and the checks' peaks.
#[derive(Debug, PartialEq)]
struct Run {
    hash: u64,
    events: u64,
    end: [i32; 2],
    peak_speed: [f64; 2],
    peak_accel: [f64; 2],
    peak_window_accel: [f64; 2],
    /// Coordination's largest disagreement, as a share of its bound (0 before it is walked).
    ratio: f64,
}

/// A controller armed and homed (its switch closed at once) at zero.
fn homed(cfg: MotionConfig) -> Controller {
    let mut c = Controller::new(cfg, SafetyConfig::BENCH).expect("a valid configuration");
    c.arm().unwrap();
    c.home().unwrap();
    c.update(
        0,
        &Inputs {
            home: true,
            ..Inputs::default()
        },
    );
    assert_eq!(c.next_step(), None);
    assert_eq!((c.state(), c.steps()), (State::Armed, [0, 0]));
    c
}

/// The schedule through the controller, every step checked. With `ahead`, the board's main loop
/// calls `update` after each step, which sets the next segment up ahead of the step interrupt;
/// without, the interrupt sets each one up itself.
fn run(cfg: MotionConfig, moves: &[Move], what: &str, ahead: bool) -> Run {
    let mut c = homed(cfg);
    c.execute(moves).unwrap_or_else(|e| panic!("{what}: {e}"));
    let mut check = TrainCheck::new(cfg, [0, 0]);
    let (mut hash, mut events) = (0xcbf2_9ce4_8422_2325u64, 0u64);
    while let Some(e) = c.next_step() {
        if ahead {
            // The clock stands at 0, as the last heartbeat (`execute`): no watchdog.
            c.update(0, &Inputs::default());
        }
        if let Err(v) = check.push(&e) {
            panic!("{what}: event {events}: {v:?}");
        }
        let word = u64::from(e.ticks) << 8
            | u64::from(e.step[0]) << 4
            | u64::from(e.step[1]) << 3
            | u64::from(e.dir[0] > 0) << 2
            | u64::from(e.dir[1] > 0);
        hash = (hash ^ word).wrapping_mul(0x100_0000_01b3);
        events += 1;
    }
    assert_eq!(c.state(), State::Armed, "{what}");
    assert_eq!(check.position(), c.steps(), "{what}");
    Run {
        hash,
        events,
        end: c.steps(),
        peak_speed: check.peak_speed_share,
        peak_accel: check.peak_accel_share,
        peak_window_accel: check.peak_window_accel_share,
        ratio: 0.0,
    }
}

/// The commanded end: the insertions and the rotations summed exactly (a spin's turns undo
/// themselves).
fn commanded(moves: &[Move]) -> [f64; 2] {
    let mut at = [0.0f64; 2];
    for m in moves {
        match *m {
            Move::Rotate { angle_deg } => at[1] += f64::from(angle_deg),
            Move::Insert { length_mm }
            | Move::InsertSpin { length_mm, .. }
            | Move::InsertDuty { length_mm, .. } => at[0] += f64::from(length_mm),
        }
    }
    at
}

/// Each coordinated segment walked alone: at every event each axis is within a step of where the
/// other's progress and the segment's ratio put it (`|d₀/n₀ − d₁/n₁| ≤ 1/n₀ + 1/n₁` for `dᵢ` of
/// `nᵢ` steps done); a spin move turns the shaft by its whole turns. Returns the largest
/// disagreement seen as a share of that bound.
fn coordination(cfg: &MotionConfig, moves: &[Move], what: &str) -> f64 {
    let mut planned = Planned { at: [0.0; 2] };
    let mut pos = [0i32; 2];
    let mut worst = 0.0f64;
    for m in moves {
        let r = planned.resolve(cfg, *m).unwrap();
        let mut turned = 0u64;
        for part in 0..r.parts() {
            let seg = r.segment(cfg, part);
            let n = [0, 1].map(|i| i64::from(seg.target[i] - pos[i]).unsigned_abs());
            let mut run = SegmentRun::new(cfg, pos, &seg);
            let mut done = [0u64; 2];
            while let Some(e) = run.next_event() {
                for i in 0..2 {
                    if e.step[i] {
                        done[i] += 1;
                        pos[i] += i32::from(e.dir[i]);
                    }
                }
                if n[0] > 0 && n[1] > 0 {
                    let share = [0, 1].map(|i| done[i] as f64 / n[i] as f64);
                    let bound = 1.0 / n[0] as f64 + 1.0 / n[1] as f64;
                    worst = worst.max((share[0] - share[1]).abs() / bound);
                }
            }
            assert_eq!(pos, seg.target, "{what}");
            turned += n[1];
        }
        if let Move::InsertSpin { turns, .. } = *m {
            let rev = cfg.to_steps(Axis::Rotation, 360.0) as u64;
            assert_eq!(turned, u64::from(turns) * rev, "{what}: a spin's turns");
        }
    }
    worst
}

/// All checks on one schedule; the run's figures.
fn check_schedule(cfg: MotionConfig, moves: &[Move], what: &str) -> Run {
    let first = run(cfg, moves, what, false);
    let exact = commanded(moves);
    for axis in Axis::BOTH {
        let i = axis as usize;
        let want = exact[i] * f64::from(cfg.axes[i].steps_per_unit);
        let off = (f64::from(first.end[i]) - want).abs();
        assert!(
            off <= 1.0,
            "{what}: {axis} ends {off} steps off the commanded"
        );
    }
    assert_eq!(
        run(cfg, moves, what, true),
        first,
        "{what}: the same schedule twice, its segments set up ahead the second time"
    );
    let worst = coordination(&cfg, moves, what);
    assert!(
        worst <= 1.0,
        "{what}: coordinated axes {worst} of a step each apart"
    );
    Run {
        ratio: worst,
        ..first
    }
}

#[test]
fn drawn_schedules_keep_every_limit_end_where_commanded_and_repeat() {
    let (mut events, mut ratio) = (0u64, 0.0f64);
    let (mut speed, mut accel, mut window) = ([0.0f64; 2], [0.0f64; 2], [0.0f64; 2]);
    for seed in 0..DRAWN {
        let (d, steps) = drawn_schedule(seed);
        let cfg = drawn_config(seed, 200.0, &d);
        let moves: Vec<Move> = steps.iter().map(|s| to_move(&s.op)).collect();
        let r = check_schedule(cfg, &moves, &format!("drawn schedule {seed}"));
        events += r.events;
        ratio = ratio.max(r.ratio);
        for i in 0..2 {
            speed[i] = speed[i].max(r.peak_speed[i]);
            accel[i] = accel[i].max(r.peak_accel[i]);
            window[i] = window[i].max(r.peak_window_accel[i]);
        }
    }
    println!(
        "{DRAWN} drawn schedules, {events} step events; peak speed {speed:.3?}, peak \
         acceleration {accel:.3?} of the limits step to step (the whole ticks' rounding in it), \
         {window:.4?} between windows of {} ms; coordination {ratio:.3} of its bound",
        needle_motion::check::WINDOW_S * 1e3
    );
    assert!(speed.iter().all(|&s| s <= 1.0));
    // The profile is constant acceleration at the limit: the windows meet it to rounding.
    assert!(window.iter().all(|&w| w <= 1.0 + 1e-3), "{window:?}");
}

#[test]
fn the_families_planned_schedules_keep_every_limit_and_end_where_commanded() {
    let mut scenarios: Vec<(String, Scenario)> = vec![("paper".into(), Scenario::paper())];
    for seed in 0..PLANNED {
        for plane in [true, false] {
            scenarios.push((
                format!("random {seed} plane {plane}"),
                random_scenario(seed, plane),
            ));
        }
    }
    let mut count = 0;
    for (name, s) in &scenarios {
        let Ok(report) = plan(s) else { continue };
        let Some(best) = report.best() else { continue };
        let sched = schedule(s, best).unwrap();
        let cfg = drawn_config(count, s.needle.length, &s.driver);
        let moves: Vec<Move> = sched.steps.iter().map(|st| to_move(&st.op)).collect();
        check_schedule(cfg, &moves, name);
        count += 1;
    }
    println!(
        "{count} of {} scenarios planned and their schedules checked",
        scenarios.len()
    );
    assert!(count >= 20, "only {count} planned");
}
