//! Each obstacle's share of the collision risk from the points of a walk kept in order: the
//! points are grouped in runs of [`RUN`], each run bounded by a ball; an obstacle is measured in
//! full only along the runs that come near enough for a chance, and one without any chance
//! anywhere (whose share is then its nearest approach) only along the runs that can hold that
//! approach. The same share bit for bit as measuring every point ([`super::risk`]'s test).

use super::obstacle_risk::{take, ObstacleRisk, ObstacleRisks};
use super::spread::TipSpread;
use crate::model::kinematics::V3;
use crate::model::scenario::{Obstacle, Scenario};

/// Points a walk may keep (half a metre at [`RISK_SPACING_MM`](super::risk::RISK_SPACING_MM)):
/// a longer walk is measured as it goes, as the device, which keeps none, measures every walk.
pub(crate) const KEPT: usize = if KEEPS { 512 } else { 0 };

/// Whether a walk is kept (on the host).
pub(crate) const KEEPS: bool = !cfg!(target_os = "none");

/// Points in a run.
const RUN: usize = 8;

/// Runs of the kept points.
const RUNS: usize = KEPT.div_ceil(RUN);

/// A point of the walk: the tip, the clearance the steering keeps there, and the clearance
/// beyond which no obstacle has a chance there.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Point {
    pub tip: TipSpread,
    pub margin: f32,
    pub quiet: f32,
}

/// The ball around a run of points and what the run's points keep.
#[derive(Clone, Copy, Debug, Default)]
struct Run {
    center: V3,
    radius: f32,
    least_margin: f32,
    most_margin: f32,
    most_quiet: f32,
}

/// `p` as the distances count it: across a plane scenario's cylinders, in the plane.
fn seen(p: V3, plane: bool) -> V3 {
    if plane {
        V3::new(0.0, p.y, p.z)
    } else {
        p
    }
}

/// Writes every obstacle's share from `points` (the whole walk, in order). False, leaving
/// `by_obstacle` as it was, when a point is not finite: every point is then measured.
pub(crate) fn shares(
    scenario: &Scenario,
    plane: bool,
    points: &[Point],
    by_obstacle: &mut ObstacleRisks,
) -> bool {
    let finite = |p: &Point| {
        p.tip.mean.iter().all(|x| x.is_finite())
            && p.tip.covariance.iter().all(|x| x.is_finite())
            && p.margin.is_finite()
            && p.quiet.is_finite()
    };
    if !points.iter().all(finite) {
        return false;
    }
    let mut runs = [Run::default(); RUNS];
    for (run, chunk) in runs.iter_mut().zip(points.chunks(RUN)) {
        let Some(first) = chunk.first() else { break };
        let center = seen(first.tip.mean, plane);
        let mut r = Run {
            center,
            radius: 0.0,
            least_margin: f32::INFINITY,
            most_margin: f32::NEG_INFINITY,
            most_quiet: 0.0,
        };
        for p in chunk {
            r.radius = r.radius.max((seen(p.tip.mean, plane) - center).norm());
            r.least_margin = r.least_margin.min(p.margin);
            r.most_margin = r.most_margin.max(p.margin);
            r.most_quiet = r.most_quiet.max(p.quiet);
        }
        *run = r;
    }
    // Every kept point lies in one of the runs.
    let runs = runs.get(..points.len().div_ceil(RUN)).unwrap_or(&runs);
    for (w, ob) in by_obstacle.iter_mut().zip(&scenario.obstacles) {
        *w = share(ob, plane, points, runs);
    }
    true
}

/// The share of `ob` over `points`, whose runs are `runs`.
fn share(ob: &Obstacle, plane: bool, points: &[Point], runs: &[Run]) -> ObstacleRisk {
    let mut w = ObstacleRisk {
        probability: 0.0,
        clearance: f32::INFINITY,
        sd: 0.0,
        steering_margin: 0.0,
    };
    let runs_of = |j: usize| points.get(j * RUN..((j + 1) * RUN).min(points.len()));
    let sound = ob.radius.is_finite() && ob.center.iter().all(|c| c.is_finite());
    if !sound {
        for p in points {
            take(&mut w, &p.tip, p.margin, ob, plane, None);
        }
        return w;
    }
    let c = seen(V3::new(ob.center[0], ob.center[1], ob.center[2]), plane);
    // The least and the most clearance a run's points can measure: they lie within its radius
    // of its centre, and the rounding of their distances stays within the slack.
    let mut bounds = [(0.0f32, 0.0f32); RUNS];
    for (b, run) in bounds.iter_mut().zip(runs) {
        let d = (run.center - c).norm();
        let slack = 1e-3 + 1e-5 * (d + run.radius + ob.radius.abs() + run.most_margin.abs());
        *b = (
            d - run.radius - ob.radius - run.most_margin - slack,
            d + run.radius - ob.radius - run.least_margin + slack,
        );
    }
    // Where a chance may arise, every point is measured, in order: the points between have no
    // chance, and a share with a chance is one of the points with a chance.
    for (j, (run, b)) in runs.iter().zip(&bounds).enumerate() {
        if b.0 <= run.most_quiet {
            for p in runs_of(j).unwrap_or(&[]) {
                take(&mut w, &p.tip, p.margin, ob, plane, None);
            }
        }
    }
    if w.probability != 0.0 {
        return w;
    }
    // No chance anywhere (so every clearance is above 0): the share is the first nearest
    // point, which lies in a run that can come as near as the nearest any run must.
    let nearest = bounds
        .iter()
        .take(runs.len())
        .fold(f32::INFINITY, |m, b| m.min(b.1));
    let mut w = ObstacleRisk {
        probability: 0.0,
        clearance: f32::INFINITY,
        sd: 0.0,
        steering_margin: 0.0,
    };
    for (j, b) in bounds.iter().take(runs.len()).enumerate() {
        if b.0 <= nearest {
            for p in runs_of(j).unwrap_or(&[]) {
                nearer(&mut w, p, ob, plane);
            }
        }
    }
    w
}

/// Takes the point `p` into `w` if it is nearer than `w`'s, where the chance is 0 at every
/// point (the share [`take`] would give, without its chance).
fn nearer(w: &mut ObstacleRisk, p: &Point, ob: &Obstacle, plane: bool) {
    let mut away = p.tip.mean - V3::new(ob.center[0], ob.center[1], ob.center[2]);
    if plane {
        away.x = 0.0;
    }
    let distance = away.norm();
    let clearance = distance - ob.radius - p.margin;
    if clearance < w.clearance {
        let sd = if distance > 0.0 {
            p.tip.sd_along(&(away / distance))
        } else {
            0.0
        };
        *w = ObstacleRisk {
            probability: 0.0,
            clearance,
            sd,
            steering_margin: p.margin,
        };
    }
}
