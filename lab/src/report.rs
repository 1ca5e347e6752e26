//! What `needle steer` prints when an insertion ends, and its exit status: one line of text per
//! figure, or with `--json` exactly one JSON object, whatever the ending (a connection refused
//! or a setup that failed too).

use super::outcome::{Class, ReadingTimes, SessionOutcome, SteerEnded};
use anyhow::Result;
use serde::Serialize;
use serde_json::json;

/// Median and largest of a latency (ms) over the readings.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Latency {
    /// Readings measured.
    pub readings: usize,
    /// Median (ms).
    pub median: f64,
    /// Largest (ms).
    pub max: f64,
}

impl Latency {
    /// Of the latencies given (`None` without any).
    pub fn of(values: &[f64]) -> Option<Latency> {
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let max = *v.last()?;
        Some(Latency {
            readings: v.len(),
            median: v[v.len() / 2],
            max,
        })
    }
}

/// `needle steer --json`.
#[derive(Serialize)]
pub struct SteerJson {
    /// The seed given, if any.
    pub seed: Option<u64>,
    /// The form steered.
    pub form: String,
    /// How it ended (`outcome`: reached, missed, collided, stopped, link_broken) and why
    /// (`stop_reason`, null: reached), with the controller's and the tracker's counts.
    #[serde(flatten)]
    pub outcome: SessionOutcome,
    /// The exit status `needle steer` gives.
    pub exit_code: u8,
    /// Tip pose received to robot command sent.
    pub latency_ms: Option<Latency>,
    /// This program's reaction: the later of the fresh pose's and the report's arrival to the
    /// command sent.
    pub reaction_ms: Option<Latency>,
    /// The pose's age when its command went out (from its sample time): the tracker's and the
    /// link's latency plus the reaction.
    pub pose_age_ms: Option<Latency>,
    /// The wait from the robot's report for a pose sampled after the piece ended.
    pub waited_ms: Option<Latency>,
}

/// A connection `needle steer` could not open: the link is broken before anything moved.
#[derive(Debug)]
pub struct Unreachable {
    /// `tracker_unreachable` or `robot_unreachable`.
    pub reason: &'static str,
    /// What failed.
    pub message: String,
}

impl std::fmt::Display for Unreachable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Unreachable {}

/// What the printing of an insertion's end needs of the command line.
#[derive(Clone, Copy, Debug)]
pub struct Printing<'a> {
    /// One JSON object instead of text.
    pub json: bool,
    /// The seed recorded (`--seed`).
    pub seed: Option<u64>,
    /// The registration awaited from the stream, and how long (ms).
    pub registration: Option<(&'a str, u64)>,
}

/// `needle steer` failed before steering: with `--json` one object says why (`stop_reason`
/// `tracker_unreachable` or `robot_unreachable`, exit status 6; else `setup_failed`, 1); the
/// error goes on to stderr with its exit status.
pub fn failed(a: Printing<'_>, form: Option<String>, e: anyhow::Error) -> Result<()> {
    let (reason, outcome, code) = match e.downcast_ref::<Unreachable>() {
        Some(u) => (u.reason, "link_broken", Class::LinkBroken.exit_code()),
        None => ("setup_failed", "not_started", 1),
    };
    if a.json {
        let j = json!({
            "seed": a.seed,
            "form": form,
            "outcome": outcome,
            "stop_reason": reason,
            "error": format!("{e:#}"),
            "exit_code": code,
        });
        println!("{j}");
    }
    if code == 1 {
        return Err(e);
    }
    Err(SteerEnded {
        code,
        message: format!("{e:#}"),
    }
    .into())
}

/// Prints how the insertion ended; an ending other than reached is an error carrying its exit
/// status.
pub fn print(a: Printing<'_>, form: String, outcome: SessionOutcome) -> Result<()> {
    let latency = Latency::of(&outcome.latencies_ms);
    let (class, stop_reason, why) = (outcome.outcome, outcome.stop_reason, outcome.why.clone());
    let outcome_on_board = outcome.on_board;
    let code = class.exit_code();
    if a.json {
        let of = |f: fn(&ReadingTimes) -> Option<f64>| {
            Latency::of(&outcome.times.iter().filter_map(f).collect::<Vec<_>>())
        };
        let (reaction_ms, pose_age_ms, waited_ms) = (
            of(|t| Some(t.reaction_ms)),
            of(|t| t.pose_age_ms),
            of(|t| Some(t.waited_ms)),
        );
        let j = SteerJson {
            seed: a.seed,
            form,
            outcome,
            exit_code: code,
            latency_ms: latency,
            reaction_ms,
            pose_age_ms,
            waited_ms,
        };
        println!("{}", serde_json::to_string(&j)?);
    } else {
        print_text(&form, &outcome, latency);
    }
    let Some(reason) = stop_reason else {
        return Ok(());
    };
    let mut message = format!("{}: {reason}", class.name());
    if let Some(why) = why {
        message = format!("{message}: {why}");
    }
    if let (Class::Stopped, "no_registration", Some((name, ms))) = (class, reason, a.registration) {
        message = format!(
            "no registration TRANSFORM named {name} came from the tracker within {ms} ms: \
             nothing was steered (the robot was told to stop)"
        );
    }
    if reason == "interrupted" {
        let mover = if outcome_on_board { "board" } else { "robot" };
        message = format!("interrupted: the {mover} was told to stop");
    }
    Err(SteerEnded { code, message }.into())
}

fn print_text(form: &str, outcome: &SessionOutcome, latency: Option<Latency>) {
    match outcome.stop_reason {
        None => println!("{form}: reached the target"),
        Some(r) => println!("{form}: stopped: {r}"),
    }
    if let Some(m) = outcome.predicted_miss_mm {
        println!("predicted miss {m:.2} mm");
    }
    let s = outcome.steering;
    let stop = match (outcome.on_board, outcome.robot_stopped) {
        (false, true) => "robot stopped",
        (false, false) => "robot did not confirm the stop",
        (true, true) => "board at rest",
        (true, false) => "board not seen at rest",
    };
    println!("{} readings, {} replans, {stop}", s.readings, s.replans);
    if let Some(l) = latency {
        println!(
            "latency pose to command: median {:.2} ms, max {:.2} ms over {} readings",
            l.median, l.max, l.readings
        );
    }
    let t = outcome.tracker;
    println!(
        "tracker: {} poses superseded, {} invalid, {} frames rejected, {} ignored",
        t.superseded_poses, t.invalid_poses, t.rejected_frames, t.ignored_frames
    );
}
