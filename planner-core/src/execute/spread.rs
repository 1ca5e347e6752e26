//! Where an executed schedule puts the tip, to first order, under the perturbation model: the
//! mean path (the torsional lag, which is systematic, turns the bevel late) and the covariance of
//! the tip's position along it.
//!
//! Every perturbation moves the path downstream of where it acts as a rigid screw, exactly as
//! the planner's own parameters do ([`Screw`](crate::model::kinematics::Screw)): the entry's
//! offset and tilt, each arc's curvature (the run's factor, shared by every arc, and the
//! segment's), a spun line's residual curvature across the heading, each push's advance error.
//! A point `P` moves by `w × P + v` per unit of a source, so its covariance is
//! `A(P) · M · A(P)ᵀ` with `A(P) = [−[P]×  I]` and `M` the sum over the independent sources
//! upstream of `P` of `σ² · s · sᵀ` (sources shared by several segments enter with their summed
//! screw). The draws are those of `needle-sim`'s world, one definition
//! ([`Perturbation`]); the tracker's figures do not enter (open loop).

use super::nominal::posture_frame;
use super::perturbation::{Perturbation, TorsionPlay, DRIFT_REFERENCE_MM};
use super::schedule::{Op, Schedule};
use crate::model::form::SegmentKind;
use crate::model::kinematics::{Frame, V3};
use crate::model::scenario::Scenario;
use nalgebra::{Matrix3, Matrix6, SMatrix, Vector6};

/// An infinitesimal rigid motion per unit of a source: angular part, then linear part.
pub(crate) type Twist = Vector6<f32>;

/// The tip's predicted position at one point of the insertion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipSpread {
    /// Needle inserted (mm, commanded).
    pub depth: f32,
    /// Where the schedule puts the tip on the nominal needle.
    pub planned: V3,
    /// The mean position under the perturbation: the planned one moved by the systematic
    /// torsional lag.
    pub mean: V3,
    /// Covariance of the position about the mean (mm²).
    pub covariance: Matrix3<f32>,
}

impl TipSpread {
    /// Standard deviation of the position along the unit direction `n` (mm).
    pub fn sd_along(&self, n: &V3) -> f32 {
        crate::fmath::sqrt((n.transpose() * self.covariance * n)[0].max(0.0))
    }
}

fn twist(w: V3, v: V3) -> Twist {
    Twist::new(w.x, w.y, w.z, v.x, v.y, v.z)
}

/// A rotation at unit rate about `axis` through `point`.
fn about(axis: V3, point: V3) -> Twist {
    twist(axis, -axis.cross(&point))
}

/// `A(P)`: how a twist moves the point `p` (`w × p + v`).
pub(crate) fn lever(p: &V3) -> SMatrix<f32, 3, 6> {
    SMatrix::<f32, 3, 6>::from_row_slice(&[
        0.0, p.z, -p.y, 1.0, 0.0, 0.0, //
        -p.z, 0.0, p.x, 0.0, 1.0, 0.0, //
        p.y, -p.x, 0.0, 0.0, 0.0, 1.0,
    ])
}

/// The twist, per unit of relative curvature change, of an arc of `length` from `start`
/// (radius `radius`): the end turns by the arc's angle more about the bending axis and moves.
fn curvature_twist(start: &Frame, length: f32, radius: f32) -> Twist {
    let a = length / radius;
    let (sn, cs) = crate::fmath::sincos(a);
    let end = start.advanced(SegmentKind::Arc, length, radius);
    let dp =
        start.e2() * (length * sn - radius * (1.0 - cs)) + start.e3() * (length * cs - radius * sn);
    let w = -start.e1() * a;
    twist(w, dp - w.cross(&end.p))
}

/// The twist per millimetre of extra advance at the end of a segment ending at `end`.
fn advance_twist(kind: SegmentKind, end: &Frame, radius: f32) -> Twist {
    match kind {
        SegmentKind::Line => twist(V3::zeros(), end.e3()),
        SegmentKind::Arc => about(-end.e1() / radius, end.p + end.e2() * radius),
    }
}

/// The two twists, per unit of drift rate along `e1` and `e2` (mm per mm), of a spun line of
/// `length` from `start`: a residual curvature 2·drift / reference bends it towards the drift.
fn drift_twists(start: &Frame, length: f32) -> [Twist; 2] {
    let end_p = start.p + start.e3() * length;
    [start.e1(), start.e2()].map(|e| {
        let dp = e * (length * length / DRIFT_REFERENCE_MM);
        let w = start.e3().cross(&e) * (2.0 * length / DRIFT_REFERENCE_MM);
        twist(w, dp - w.cross(&end_p))
    })
}

/// The run of the propagation: what has accumulated upstream of the tip.
pub(crate) struct Sources {
    /// Independent sources already complete: Σ σ² s sᵀ.
    pub done: Matrix6<f32>,
    /// The run's curvature factor, shared by every arc (per unit factor).
    pub run_curvature: Twist,
    /// The current segment's curvature factor (consecutive pushes share one draw).
    pub segment_curvature: Twist,
    /// The current spun line's drift rates (consecutive spins share one draw).
    pub drift: [Twist; 2],
}

/// `m += σ² s sᵀ`.
pub(crate) fn add_outer(m: &mut Matrix6<f32>, s: &Twist, variance: f32) {
    crate::matmul::add_outer(m, s, s, variance);
}

/// Propagates the spread along `schedule` executed in `scenario` under `p`; `visit` sees the
/// tip at the posture and at points of every push no more than `spacing` mm apart (at least
/// one per push). Returns the tip at the end.
///
/// ```
/// use planner_core::execute::perturbation::Perturbation;
/// use planner_core::execute::schedule::schedule;
/// use planner_core::execute::spread::propagate;
/// use planner_core::{plan, Scenario};
///
/// let scenario = Scenario::paper();
/// let best = plan(&scenario).unwrap().best().unwrap().clone();
/// let s = schedule(&scenario, &best).unwrap();
/// let end = propagate(&scenario, &s, &Perturbation::default(), 1.0, |_| {});
/// // A millimetre or two of spread at the end of a 91 mm insertion, none without perturbation.
/// let sd = end.covariance.trace().sqrt();
/// assert!(sd > 0.5 && sd < 5.0);
/// let exact = propagate(&scenario, &s, &Perturbation::none(), 1.0, |_| {});
/// assert!(exact.covariance.norm() < 1e-9 && (exact.mean - exact.planned).norm() < 1e-4);
/// ```
pub fn propagate(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    spacing: f32,
    mut visit: impl FnMut(&TipSpread),
) -> TipSpread {
    let mut tip = None;
    walk(scenario, schedule, p, spacing, &mut |at| {
        let t = spread_at(at.src, at.part, p, at.depth, at.planned, at.mean);
        visit(&t);
        tip = Some(t);
    });
    // The walk visits the posture at least.
    tip.unwrap_or(TipSpread {
        depth: 0.0,
        planned: V3::zeros(),
        mean: V3::zeros(),
        covariance: Matrix3::zeros(),
    })
}

/// One point of the walk along a schedule: the sources upstream of it and the push under way.
pub(crate) struct WalkPoint<'a> {
    pub src: &'a Sources,
    pub part: &'a Partial,
    /// Needle inserted (mm, commanded).
    pub depth: f32,
    pub planned: V3,
    pub mean: V3,
    /// The shared draw of segment curvature and drift under way (counted from 0; one per run
    /// of pushes of one kind).
    pub group: usize,
    /// The push under way (counted from 0; `None` at the posture).
    pub push: Option<usize>,
}

/// Walks `schedule` as [`propagate`] describes, handing `at` each point. One copy serves every
/// caller (`dyn`, never inlined): on the device each copy cost kilobytes of flash.
#[inline(never)]
pub(crate) fn walk(
    scenario: &Scenario,
    schedule: &Schedule,
    p: &Perturbation,
    spacing: f32,
    at: &mut dyn FnMut(&WalkPoint),
) {
    let radius = scenario.needle.curvature_radius;
    let spacing = if spacing > 0.0 { spacing } else { 1.0 };
    let mut planned = posture_frame(scenario, schedule);
    let mut mean = planned;
    let mut src = Sources {
        done: entry_sources(&mean, p),
        run_curvature: Twist::zeros(),
        segment_curvature: Twist::zeros(),
        drift: [Twist::zeros(); 2],
    };
    // The mean path turns the bevel where the simulated world does.
    let mut torsion = TorsionPlay::new(p);
    let mut depth = 0.0f32;
    let mut last = None;
    let (mut group, mut push) = (0usize, 0usize);
    at(&WalkPoint {
        src: &src,
        part: &Partial::NONE,
        depth,
        planned: planned.p,
        mean: mean.p,
        group,
        push: None,
    });
    for step in &schedule.steps {
        let Some((kind, length, r)) = step.op.segment(radius) else {
            if let Op::Rotate { angle_deg } = step.op {
                planned = planned.rolled(angle_deg.to_radians());
                mean = mean.rolled(torsion.rotate(angle_deg, depth).to_radians());
            }
            last = None;
            continue;
        };
        // A duty-cycled push bends by its share of the curvature and drifts as a spun line:
        // the world draws its factor and its drift afresh after any other step.
        let duty = matches!(step.op, Op::InsertDuty { .. });
        let key = (kind, duty);
        if last != Some(key) {
            if push > 0 {
                group += 1;
            }
            src.flush(p);
        }
        last = Some(key);
        let pieces = libm::ceilf(length / spacing).max(1.0) as u32;
        let advance_sd = p.insertion_error_mm * crate::fmath::sqrt(length.max(0.0) / 100.0);
        for k in 1..=pieces {
            let t = length * k as f32 / pieces as f32;
            let shared = advance_sd * t / length.max(1e-6);
            let part = Partial::of(kind, duty, &mean, t, r, shared);
            at(&WalkPoint {
                src: &src,
                part: &part,
                depth: depth + t,
                planned: planned.point_at(kind, t, r),
                mean: mean.point_at(kind, t, r),
                group,
                push: Some(push),
            });
            if k == pieces {
                src.complete(&part, advance_sd);
            }
        }
        push += 1;
        depth += length;
        planned = planned.advanced(kind, length, r);
        mean = mean.advanced(kind, length, r);
        if kind == SegmentKind::Line || duty {
            mean = mean.rolled(torsion.spin_settles(depth).to_radians());
        }
    }
}

/// The entry's offset (per axis) and tilt (about the posture frame's `e1` and `e2`).
fn entry_sources(start: &Frame, p: &Perturbation) -> Matrix6<f32> {
    let mut m = Matrix6::zeros();
    let offset = p.entry_position_mm * p.entry_position_mm;
    for axis in [V3::x(), V3::y(), V3::z()] {
        add_outer(&mut m, &twist(V3::zeros(), axis), offset);
    }
    let tilt = p.entry_direction_deg.to_radians();
    for axis in [start.e1(), start.e2()] {
        add_outer(&mut m, &about(axis, start.p), tilt * tilt);
    }
    m
}

/// The sources of the push under way, up to a point of it.
pub(crate) struct Partial {
    pub curvature: Twist,
    pub drift: [Twist; 2],
    pub advance: Twist,
    pub advance_sd: f32,
}

impl Partial {
    pub(crate) const NONE: Partial = Partial {
        curvature: Twist::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        drift: [Twist::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0); 2],
        advance: Twist::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        advance_sd: 0.0,
    };

    /// A push of `kind` (duty-cycled or not) from `start`, `t` mm into it; the advance error
    /// drawn for the whole push is shared out along it (`advance_sd` at `t`).
    fn of(
        kind: SegmentKind,
        duty: bool,
        start: &Frame,
        t: f32,
        radius: f32,
        advance_sd: f32,
    ) -> Partial {
        let end = start.advanced(kind, t, radius);
        let mut part = Partial {
            advance: advance_twist(kind, &end, radius),
            advance_sd,
            ..Partial::NONE
        };
        if kind == SegmentKind::Arc {
            part.curvature = curvature_twist(start, t, radius);
        }
        if kind == SegmentKind::Line || duty {
            part.drift = drift_twists(start, t);
        }
        part
    }
}

impl Sources {
    /// Ends the shared draw of the segment or line before a change of kind or a rotation.
    fn flush(&mut self, p: &Perturbation) {
        let seg = p.segment_curvature_spread;
        add_outer(&mut self.done, &self.segment_curvature, seg * seg);
        let drift = p.line_drift_mm_per_mm;
        for d in &self.drift {
            add_outer(&mut self.done, d, drift * drift);
        }
        self.segment_curvature = Twist::zeros();
        self.drift = [Twist::zeros(); 2];
    }

    /// Adds a finished push: its curvature to the shared draws, its advance error as its own.
    fn complete(&mut self, part: &Partial, advance_sd: f32) {
        self.run_curvature += part.curvature;
        self.segment_curvature += part.curvature;
        for (d, add) in self.drift.iter_mut().zip(&part.drift) {
            *d += add;
        }
        add_outer(&mut self.done, &part.advance, advance_sd * advance_sd);
    }

    /// Σ σ² s sᵀ at a point `part` of the way into the push under way.
    pub(crate) fn at(&self, part: &Partial, p: &Perturbation) -> Matrix6<f32> {
        let (run, seg, drift) = (
            p.curvature_spread,
            p.segment_curvature_spread,
            p.line_drift_mm_per_mm,
        );
        let mut m = self.done;
        add_outer(&mut m, &(self.run_curvature + part.curvature), run * run);
        add_outer(
            &mut m,
            &(self.segment_curvature + part.curvature),
            seg * seg,
        );
        for (d, add) in self.drift.iter().zip(&part.drift) {
            add_outer(&mut m, &(d + add), drift * drift);
        }
        add_outer(&mut m, &part.advance, part.advance_sd * part.advance_sd);
        m
    }
}

fn spread_at(
    src: &Sources,
    part: &Partial,
    p: &Perturbation,
    depth: f32,
    planned: V3,
    mean: V3,
) -> TipSpread {
    let a = lever(&mean);
    let covariance = crate::matmul::sandwich(&a, &src.at(part, p));
    TipSpread {
        depth,
        planned,
        mean,
        covariance,
    }
}
