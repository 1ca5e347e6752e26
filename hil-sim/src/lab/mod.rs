//! The simulated lab: the robot, tissue and tracker of `needle simulate` (needle-sim's
//! [`World`]) behind the lab link, so that `needle steer` runs end to end on one machine.
//!
//! - The tracker is an OpenIGTLink server as PLUS is ([`tracker`]): every client gets each pose
//!   the world measures, a `TRANSFORM` named `TargetToReference` (the target as imaging sees it)
//!   then one named `NeedleTipToReference` (the tip frame: e2 the bevel, e3 the heading); with a
//!   stream rate it also repeats the newest pose at that rate.
//! - The robot is an OpenIGTLink server speaking the robot mapping of
//!   [`needle_lab::robot`]: it takes a step list, executes it piece by piece exactly as
//!   [`World::execute`] does, reports each piece's progress and waits for the host's word (go
//!   on, a new step list replacing the rest from that piece, hold, or stop). One robot connection
//!   is one insertion; the k-th (from 0) runs in the world of seed `seed + k`.
//!
//! Lock-step: the tracker sends a piece's pose before the robot reports the piece, and nothing
//! moves until the host answers, so an insertion equals `needle simulate --closed-loop` for that
//! seed bit for bit. `rate_hz` paces the pieces (at most that many a second), `latency_ms`
//! delays each pose; neither changes a figure.
//!
//! The world is the one `needle simulate` makes of the scenario and its flags (the setup's
//! perturbation, world effects and tracker faults): a 5-DOF sensor's pose goes out with a roll
//! of no meaning ([`tracker`]), a reading without a new image without the target, a dropout as
//! a tip flagged invalid, an outlier at its offset position. The effects' time (latency,
//! imaging) is the world's clock, not the wall's, so lock-step reproduces them too.

mod board;
mod robot;
pub mod tracker;

use anyhow::{anyhow, bail, Context, Result};
use needle_igtl::Timestamp;
use needle_lab::robot::{RobotCommand, RobotReport};
use needle_lab::wire::now;
use needle_sim::{finish, Measurement, Tracker, TrackerFaults, World};
use needle_simulate::setup::Setup;
use planner_core::execute::schedule::{Op, Posture, Step};
use planner_core::model::kinematics::V3;
use planner_core::model::scenario::Workspace;
use robot::{Robot, Word};
use serde::Serialize;
use std::net::{TcpListener, TcpStream};
use std::ops::ControlFlow;
use std::time::{Duration, Instant};
pub use tracker::{TrackerClients, TrackerConfig};

/// How the lab runs.
#[derive(Clone, Copy, Debug, Default)]
pub struct LabConfig {
    /// Seed of the first insertion's world.
    pub seed: u64,
    /// Pieces a second at most (0: as fast as the host answers).
    pub rate_hz: f64,
    /// Delay of each pose after its piece (ms).
    pub latency_ms: u64,
    /// Delay of each piece's report after its pose went out (ms): a robot whose word travels
    /// slower than the tracker's stream, so that the stream's copies of the new pose arrive
    /// before the report.
    pub report_delay_ms: u64,
    /// Test fault: the tracker sends no pose after this many in an insertion.
    pub tracker_silent_after: Option<u32>,
    /// Test fault: the robot reports nothing after this many pieces in an insertion.
    pub robot_silent_after: Option<u32>,
    /// Test fault: every this many poses one is flagged invalid, alternately by v3 metadata
    /// (`TransformStatus` = `INVALID`) and by a tip `STATUS` that is not OK sent before it (and
    /// an OK one after it).
    pub invalid_every: Option<u32>,
    /// Test fault: after this many pieces the robot reports 5 mm more depth than it did.
    pub robot_misreport_after: Option<u32>,
    /// How far the robot's clock runs ahead of the machine's (ms; negative: behind): its
    /// reports' stamps are moved so.
    pub robot_clock_offset_ms: i64,
    /// Test fault: after this many pieces the robot's contact sensor fires wherever the tip is
    /// (it reports `collided` and stops).
    pub robot_collides_after: Option<u32>,
    /// The robot's absolute base roll when an insertion begins (degrees): it turns from there
    /// to the posture's roll by the shorter way, and reports absolute rolls.
    pub robot_start_roll_deg: f64,
    /// The robot holds the needle in a fixed guide along the entry axis: it refuses a posture
    /// that tilts it.
    pub robot_fixed_guide: bool,
    /// In real time: each piece takes its share of its step's duration times this factor
    /// (none: lock-step, a piece takes no time).
    pub time_scale: Option<f64>,
}

/// How a pose is flagged invalid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Flag {
    Metadata,
    Status,
}

/// How an insertion ended, from the robot's side.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum End {
    /// The host said stop.
    Stopped,
    /// The step list ran out (then the host said stop, or left).
    Done,
    /// The host left mid-insertion.
    ConnectionLost,
    /// The robot sensed the tip in an obstacle, reported `collided` and stopped.
    Collided,
}

/// One insertion's true figures, printed as a JSON line: the world's truth, which the host
/// cannot see.
#[derive(Clone, Debug, Serialize)]
pub struct LabRun {
    /// The world's seed.
    pub seed: u64,
    /// How it ended.
    pub end: End,
    /// Pieces executed.
    pub pieces: u32,
    /// Distance of the true tip to the true target (mm).
    pub target_error: f32,
    /// RMS distance of the true path to the planned one (mm).
    pub path_rms: f32,
    /// Largest distance of the true path to the planned one (mm).
    pub path_max: f32,
    /// The true path entered an obstacle.
    pub collided: bool,
    /// Smallest clearance of the true path (mm).
    pub min_clearance: f32,
}

impl LabRun {
    fn of(seed: u64, end: End, pieces: u32, run: &needle_sim::Run) -> LabRun {
        LabRun {
            seed,
            end,
            pieces,
            target_error: run.target_error,
            path_rms: run.path_rms,
            path_max: run.path_max,
            collided: run.collided,
            min_clearance: run.min_clearance,
        }
    }
}

/// A vector made unit length.
fn unit(v: [f32; 3]) -> [f32; 3] {
    let n = v
        .iter()
        .map(|x| x * x)
        .sum::<f32>()
        .sqrt()
        .max(f32::MIN_POSITIVE);
    v.map(|x| x / n)
}

/// What the tracker reports of the world's measurement `m` once `faults` had their say: `m`
/// (at an outlier's position), and whether the pose dropped out. The fault stream draws as in
/// `needle simulate`'s closed loop, so a seed drops and displaces the same readings.
fn tracked(faults: &mut Tracker, m: &Measurement) -> (Measurement, bool) {
    let pose = faults.readings(m).first().and_then(|(r, _)| r.pose);
    match pose {
        Some(p) => (
            Measurement {
                position: p.position,
                ..*m
            },
            false,
        ),
        None => (*m, true),
    }
}

/// Refuses the tracker faults the lab cannot serve as `needle simulate` injects them: a reading
/// sent twice, and an old one sent after a new one, reach the simulated controller (which
/// counts them) but never `needle steer`'s (which uses a sample once, by its timestamp).
pub fn check_faults(f: &TrackerFaults) -> Result<()> {
    for (key, rate) in [("repeat_rate", f.repeat_rate), ("stale_rate", f.stale_rate)] {
        anyhow::ensure!(
            rate == 0.0,
            "--fault {key} = {rate}: the lab does not serve it (`needle steer` uses a tracker \
             sample once, so its controller would not see what the simulated one does)"
        );
    }
    Ok(())
}

/// The simulated lab: one planned insertion, served to robot clients one after the other.
pub struct Lab {
    /// The insertion (as `needle simulate --closed-loop` sets it up).
    pub setup: Setup,
    /// How it runs.
    pub config: LabConfig,
    /// The tracker's clients.
    pub tracker: TrackerClients,
}

impl Lab {
    /// Serves insertions on `robot` for ever, each one's figures to `on_run`.
    pub fn serve(&self, robot: TcpListener, mut on_run: impl FnMut(&LabRun)) -> Result<()> {
        for (k, conn) in (0u64..).zip(robot.incoming()) {
            let seed = self.config.seed.wrapping_add(k);
            match conn
                .map_err(anyhow::Error::from)
                .and_then(|c| self.insert(c, seed))
            {
                Ok(run) => on_run(&run),
                Err(e) => eprintln!("hil-sim lab: insertion {k} (seed {seed}): {e:#}"),
            }
        }
        Ok(())
    }

    /// One insertion in the world of `seed`, commanded over `conn`.
    pub fn insert(&self, conn: TcpStream, seed: u64) -> Result<LabRun> {
        let s = &self.setup;
        let schedule = &s.prepared.schedule;
        let (p, effects) = (&s.perturbation, &s.effects);
        let mut robot = Robot::new(
            conn,
            self.config.robot_silent_after,
            self.config.robot_clock_offset_ms,
        )?;
        let (posture, base0_deg, steps) = self.start(&mut robot)?;
        // The needle starts where the robot set it: the plan's posture if it was commanded.
        let mut at = schedule.clone();
        at.posture = posture;
        let mut world =
            World::with_effects(&s.scenario, &at, p, effects, seed).map_err(|e| anyhow!("{e}"))?;
        let Some(mut steps) = steps else {
            let run = finish(&world, &s.planned, seed);
            return Ok(LabRun::of(seed, End::Stopped, 0, &run));
        };
        let mut faults = Tracker::new(&s.faults, seed);
        self.tracker.wait_for_one()?;
        let mut end = None;
        let mut last_piece = Instant::now();
        let mut was = (0.0, 0.0);
        while end.is_none() {
            let mut next = None;
            for step in &steps {
                let mut failure = None;
                world.execute_seen(step, |m, tip, _| {
                    self.pace(&mut last_piece);
                    self.take_time(step, m, &mut was);
                    robot.pieces += 1;
                    let ended = match self.show(&mut faults, m, robot.pieces) {
                        Ok(ended) => ended,
                        Err(e) => {
                            failure = Some(e);
                            return ControlFlow::Break(());
                        }
                    };
                    std::thread::sleep(Duration::from_millis(self.config.report_delay_ms));
                    if self.senses_collision(robot.pieces, tip.p) {
                        robot.report_at(
                            RobotReport::Collided {
                                depth_mm: m.depth_mm,
                            },
                            ended,
                        );
                        end = Some(End::Collided);
                        return ControlFlow::Break(());
                    }
                    // Stamped when the piece ended, as its pose was sampled.
                    robot.report_at(
                        RobotReport::Progress {
                            piece: robot.pieces,
                            depth_mm: m.depth_mm + self.misreport(robot.pieces),
                            base_deg: base0_deg + f64::from(m.base_deg),
                        },
                        ended,
                    );
                    match robot.word() {
                        Word::Go => return ControlFlow::Continue(()),
                        Word::Replace(s) => next = Some(s),
                        Word::Stop => end = Some(End::Stopped),
                        Word::Lost => end = Some(End::ConnectionLost),
                    }
                    ControlFlow::Break(())
                });
                if let Some(e) = failure {
                    return Err(e);
                }
                if end.is_some() || next.is_some() {
                    break;
                }
            }
            match next {
                Some(s) => steps = s,
                None if end.is_none() => {
                    robot.report(RobotReport::Done);
                    // The insertion is over whatever the host says now; a stop is answered.
                    if let Word::Stop = robot.word() {
                        robot.report(RobotReport::Stopped);
                    }
                    end = Some(End::Done);
                }
                None => {}
            }
        }
        if end == Some(End::Stopped) {
            robot.report(RobotReport::Stopped);
        }
        let run = finish(&world, &s.planned, seed);
        let end = end.unwrap_or(End::ConnectionLost);
        Ok(LabRun::of(seed, end, robot.pieces, &run))
    }

    /// The start of an insertion: the posture (taken, or refused by a fixed guide asked to
    /// tilt), then the first step list. Gives the posture the needle is set at (without a
    /// `posture` command: along the entry axis at the robot's own roll), the absolute base roll
    /// it took, and the steps (none: the host stopped before steering, and heard it stopped).
    fn start(&self, robot: &mut Robot) -> Result<(Posture, f64, Option<Vec<Step>>)> {
        let planned = self.setup.prepared.schedule.posture;
        let start = self.config.robot_start_roll_deg;
        let mut posture = Posture {
            theta1_deg: 0.0,
            theta2_deg: 0.0,
            roll_deg: start as f32,
            direction: unit(self.setup.scenario.entry.direction),
            ..planned
        };
        let mut base0_deg = start;
        loop {
            match robot.commands.recv() {
                Ok(RobotCommand::Posture {
                    theta1_deg,
                    theta2_deg,
                    roll_deg,
                }) => {
                    if self.config.robot_fixed_guide && (theta1_deg, theta2_deg) != (0.0, 0.0) {
                        robot.report(RobotReport::PostureRefused { max_tilt_deg: 0.0 });
                        continue;
                    }
                    // The shorter way round from where the base is to the roll asked.
                    let r = f64::from(roll_deg);
                    base0_deg = r + 360.0 * ((start - r) / 360.0 + 0.5).floor();
                    posture = Posture {
                        theta1_deg,
                        theta2_deg,
                        roll_deg,
                        direction: if (theta1_deg, theta2_deg) == (0.0, 0.0) {
                            posture.direction
                        } else {
                            planned.direction
                        },
                        ..planned
                    };
                    robot.report(RobotReport::PostureSet {
                        depth_mm: 0.0,
                        base_deg: base0_deg,
                    });
                }
                Ok(RobotCommand::Steps { count }) => {
                    let steps = robot
                        .steps(count)
                        .context("the host's step list broke off")?;
                    return Ok((posture, base0_deg, Some(steps)));
                }
                // Before the first piece too, a `hold` is answered at once (the host times
                // these exchanges to bound the robot's clock).
                Ok(RobotCommand::Hold) => robot.report(RobotReport::Holding),
                Ok(RobotCommand::Stop) => {
                    // A host that gave up before steering (no registration came, a posture
                    // refused) hears it stopped.
                    robot.report(RobotReport::Stopped);
                    return Ok((posture, base0_deg, None));
                }
                Ok(_) => {}
                Err(_) => bail!("the host sent no step list"),
            }
        }
    }

    /// The error the robot adds to the depth it reports for piece `k`.
    fn misreport(&self, k: u32) -> f32 {
        match self.config.robot_misreport_after {
            Some(n) if k > n => 5.0,
            _ => 0.0,
        }
    }

    /// The tracker shows the tip as `m` measures it at the end of piece `k` (through its faults,
    /// or not at all once silent): gives the instant the piece ended, as stamped.
    fn show(&self, faults: &mut Tracker, m: &Measurement, k: u32) -> Result<Timestamp> {
        if self.config.tracker_silent_after.is_some_and(|n| k > n) {
            self.tracker.silence();
            return Ok(now());
        }
        let (m, dropped) = tracked(faults, m);
        let flag = if dropped {
            Some(Flag::Metadata)
        } else {
            self.flag(k)
        };
        self.tracker.publish(&m, flag, k)
    }

    /// Whether the robot's contact sensor fires after piece `k` with the true tip at `tip`: the
    /// tip inside an obstacle (a circle of a plane scenario is a cylinder across it), or the
    /// test fault's piece reached. A path that grazes an obstacle between two piece ends (at
    /// most 1 mm apart) goes unsensed, as a sensor's threshold lets a graze pass.
    fn senses_collision(&self, k: u32, tip: V3) -> bool {
        if self.config.robot_collides_after.is_some_and(|n| k > n) {
            return true;
        }
        let plane = self.setup.scenario.options.workspace == Workspace::PlaneYz;
        self.setup.scenario.obstacles.iter().any(|o| {
            let d = [
                tip.x - o.center[0],
                tip.y - o.center[1],
                tip.z - o.center[2],
            ];
            let across = if plane { 0.0 } else { d[0] * d[0] };
            across + d[1] * d[1] + d[2] * d[2] < o.radius * o.radius
        })
    }

    /// How the pose of piece `k` is flagged invalid, if it is.
    fn flag(&self, k: u32) -> Option<Flag> {
        let every = self.config.invalid_every.filter(|&n| n > 0)?;
        k.is_multiple_of(every).then(|| {
            if (k / every) % 2 == 1 {
                Flag::Metadata
            } else {
                Flag::Status
            }
        })
    }

    /// In real time, the piece takes its share of its step's duration (scaled) before it ends:
    /// the tracker samples the tip as it was meanwhile. `was` is the depth and roll before it.
    fn take_time(&self, step: &Step, m: &Measurement, was: &mut (f32, f32)) {
        let moved = (m.depth_mm - was.0, m.base_deg - was.1);
        *was = (m.depth_mm, m.base_deg);
        let Some(scale) = self.config.time_scale else {
            return;
        };
        let share = match step.op {
            Op::Rotate { angle_deg } if angle_deg != 0.0 => (moved.1 / angle_deg).abs(),
            op if op.inserted_mm() > 0.0 => (moved.0 / op.inserted_mm()).abs(),
            _ => 1.0,
        };
        let seconds = f64::from(step.duration_s * share.min(1.0)) * scale;
        if seconds.is_finite() && seconds > 0.0 {
            std::thread::sleep(Duration::from_secs_f64(seconds.min(60.0)));
        }
    }

    /// Waits out the rate and the latency before a piece's pose goes out.
    fn pace(&self, last_piece: &mut Instant) {
        if self.config.rate_hz > 0.0 {
            let period = Duration::from_secs_f64(1.0 / self.config.rate_hz);
            let due = *last_piece + period;
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
        }
        *last_piece = Instant::now();
        std::thread::sleep(Duration::from_millis(self.config.latency_ms));
    }
}
