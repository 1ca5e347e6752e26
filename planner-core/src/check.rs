//! The independent check every reported plan passes: the path is rebuilt from the *reported*
//! numbers (insertion angles, segment kinds, lengths and bevel angles), not from the optimiser's
//! state, and its end point, every clearance and every bound are measured afresh.

use crate::model::broad::{worth_a_tree, Broad, Set};
use crate::model::clearance::closest;
use crate::model::form::{Form, SegmentKind};
use crate::model::kinematics::{entry_basis, insertion_frame, PathGeometry, V3};
use crate::model::scenario::{RiskMeasure, Scenario};
use crate::report::{Insertion, SegmentPlan};
use crate::MAX_CONTROL_DEGREE;

/// What the check measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// Distance from the rebuilt end point to the target (mm).
    pub target_error: f32,
    /// Smallest clearance to any obstacle surface (mm; infinite without obstacles).
    pub min_clearance: f32,
    /// Total length L (mm).
    pub length: f32,
    /// Risk degree D of the rebuilt path (infinite when it touches or enters an obstacle).
    pub risk: f32,
    /// Every segment within its length bounds (arcs joined by a bevel rotation under
    /// [`ARC_JOIN_DEG`] counted as one arc), the whole path within the needle's insertable
    /// length, and the posture within the tilt bound.
    pub within_bounds: bool,
    /// All three conditions hold: end within tolerance, clearance above the minimum, bounds.
    pub feasible: bool,
}

/// A bevel rotation smaller than this (degrees, either way) turns the bevel by nothing a driver
/// executes: the schedule leaves it out, and the arcs on either side of it are one arc, held to
/// the needle's longest arc. (The end moves by less than 0.01 mm over an arc of 100 mm.)
pub const ARC_JOIN_DEG: f32 = 0.01;

/// Every run of arcs joined by rotations under [`ARC_JOIN_DEG`] no longer than `max_arc`.
fn joined_arcs_within(segments: &[SegmentPlan], max_arc: f32) -> bool {
    let mut run = 0.0f32;
    let mut previous_arc = false;
    for s in segments {
        if s.kind != SegmentKind::Arc {
            previous_arc = false;
            continue;
        }
        let turn = libm::fmodf(libm::fabsf(s.bevel_deg), 360.0);
        let joined = previous_arc && (turn < ARC_JOIN_DEG || 360.0 - turn < ARC_JOIN_DEG);
        run = if joined { run + s.length } else { s.length };
        if !(run <= max_arc + max_arc * 1e-5) {
            return false;
        }
        previous_arc = true;
    }
    true
}

/// Rebuilds the path that `insertion` and `segments` describe.
pub fn rebuild(
    scenario: &Scenario,
    form: Form,
    insertion: &Insertion,
    segments: &[SegmentPlan],
) -> PathGeometry {
    let e = &scenario.entry;
    let basis = entry_basis(e.direction);
    let p0 = V3::new(e.position[0], e.position[1], e.position[2]);
    let first = insertion_frame(
        p0,
        &basis,
        insertion.theta1_deg.to_radians(),
        insertion.theta2_deg.to_radians(),
    );
    let mut lengths = [0.0; MAX_CONTROL_DEGREE];
    let mut bevels = [0.0; MAX_CONTROL_DEGREE];
    for (i, s) in segments.iter().take(MAX_CONTROL_DEGREE).enumerate() {
        lengths[i] = s.length;
        bevels[i] = s.bevel_deg.to_radians();
    }
    PathGeometry::build(form, first, &lengths, &bevels, scenario.planned_radius())
}

/// Checks a reported path against the scenario.
///
/// ```
/// use planner_core::check::check;
/// use planner_core::{plan, Scenario};
///
/// let scenario = Scenario::paper();
/// let report = plan(&scenario).unwrap();
/// let best = report.best().unwrap();
/// let verdict = check(&scenario, best.form, &best.insertion, &best.segments);
/// assert!(verdict.feasible && verdict.target_error <= scenario.target.tolerance);
/// assert_eq!(verdict.length, best.length);
///
/// // The same path with its last segment 5 mm longer overshoots the target.
/// let mut longer = best.segments.clone();
/// longer.last_mut().unwrap().length += 5.0;
/// let verdict = check(&scenario, best.form, &best.insertion, &longer);
/// assert!(!verdict.feasible && verdict.target_error > 4.0);
/// ```
pub fn check(
    scenario: &Scenario,
    form: Form,
    insertion: &Insertion,
    segments: &[SegmentPlan],
) -> Verdict {
    let geo = rebuild(scenario, form, insertion, segments);
    let t = scenario.target.position;
    let target = V3::new(t[0], t[1], t[2]);
    let target_error = (geo.end() - target).norm();
    let (min_clearance, inverse_sum) = clearances(scenario, &geo);
    let risk = match scenario.options.risk {
        RiskMeasure::Mean if !scenario.obstacles.is_empty() => {
            inverse_sum / scenario.obstacles.len() as f32
        }
        _ => inverse_sum,
    };
    let max_arc = scenario.planned_radius() * scenario.needle.max_arc_deg.to_radians();
    let max_line = scenario.max_line_length();
    // Bounds are checked with a relative slack of one part in 10^5 (f32 rounding of the report).
    let slack = |bound: f32| bound * 1e-5;
    let lengths_ok = segments.len() == form.len()
        && segments.iter().enumerate().all(|(i, s)| {
            let max = match form.kind(i) {
                SegmentKind::Arc => max_arc,
                SegmentKind::Line => max_line,
            };
            s.kind == form.kind(i)
                && s.length.is_finite()
                && s.length >= 0.0
                && s.length <= max + slack(max)
        });
    let basis = entry_basis(scenario.entry.direction);
    let nominal: V3 = basis.column(2).into();
    let heading = insertion_frame(
        V3::zeros(),
        &basis,
        insertion.theta1_deg.to_radians(),
        insertion.theta2_deg.to_radians(),
    )
    .e3();
    let tilt = heading.dot(&nominal);
    let cos_max = crate::fmath::cos(scenario.entry.max_tilt_deg.to_radians());
    let tilt_ok = tilt >= cos_max - 1e-6;
    let length = geo.total_length();
    let needle = scenario.needle.length;
    let within_bounds = lengths_ok
        && joined_arcs_within(segments, max_arc)
        && length <= needle + slack(needle)
        && tilt_ok;
    // A clearance passes only by more than the scenario's resolution (four f32 units in the last
    // place of its coordinates): this check's own rounding must not pass a path that exact
    // arithmetic puts short of the minimum (found by fuzzing: a path kept the minimum in f32 and
    // fell 8e-6 mm short of it in f64). The optimiser keeps twice that margin.
    let clearance_floor = scenario.options.min_clearance.max(0.0) + scenario.resolution();
    let feasible = target_error.is_finite()
        && target_error <= scenario.target.tolerance
        && min_clearance > clearance_floor
        && within_bounds;
    Verdict {
        target_error,
        min_clearance,
        length,
        risk,
        within_bounds,
        feasible,
    }
}

/// The smallest clearance of `geo` to any sphere and the sum of the spheres' inverse clearances
/// (as the risk degree counts them). With `risk_within_mm`, the spheres farther than it add
/// nothing, so only those a broad phase of the check's own (never the optimiser's) finds near
/// the path are measured, the reach growing until the nearest lies within it: the same numbers
/// as measuring every sphere.
pub fn clearances(scenario: &Scenario, geo: &PathGeometry) -> (f32, f32) {
    let obstacles = &scenario.obstacles;
    let Some(within) = scenario
        .options
        .risk_within_mm
        .filter(|r| *r > 0.0 && r.is_finite())
    else {
        return clearances_of(scenario, geo, &Set::all(obstacles.len()));
    };
    // The distance to a line costs less than a look-up in the tree, and the tree's building
    // more than a few arcs' distances: a tree for many spheres along a path with an arc.
    let arcs = (0..geo.form.len()).any(|i| geo.form.kind(i) == SegmentKind::Arc);
    if !worth_a_tree(obstacles.len()) || !arcs {
        return clearances_of(scenario, geo, &Set::all(obstacles.len()));
    }
    let broad = Broad::new(obstacles);
    let mut reach = within;
    for _ in 0..REACH_GROWTHS {
        let near = broad.near_path(obstacles, geo, reach);
        let (least, sum) = clearances_of(scenario, geo, &near);
        // A sphere left out is at least `reach` away: it neither adds to the sum (`reach` is
        // at least `within`) nor comes nearer than the nearest found within the reach.
        if least < reach {
            return (least, sum);
        }
        reach *= 4.0;
    }
    clearances_of(scenario, geo, &Set::all(obstacles.len()))
}

/// Times the check's reach grows fourfold before every sphere is measured.
const REACH_GROWTHS: usize = 6;

/// [`clearances`] over the spheres of `set`, in index order.
pub fn clearances_of(scenario: &Scenario, geo: &PathGeometry, set: &Set) -> (f32, f32) {
    let mut min_clearance = f32::INFINITY;
    let mut inverse_sum = 0.0f32;
    for o in set.iter() {
        let Some(ob) = scenario.obstacles.get(o) else {
            continue;
        };
        let c = V3::new(ob.center[0], ob.center[1], ob.center[2]);
        let mut clearance = f32::INFINITY;
        for i in 0..geo.form.len() {
            let kind = geo.form.kind(i);
            let d = closest(&geo.starts[i], kind, geo.lengths[i], geo.radius, &c);
            clearance = clearance.min(d.distance - ob.radius);
        }
        min_clearance = min_clearance.min(clearance);
        inverse_sum += match scenario.options.risk_within_mm {
            _ if !(clearance > 0.0) => f32::INFINITY,
            None => 1.0 / clearance,
            Some(r) if clearance < r => 1.0 / clearance - 1.0 / r,
            Some(_) => 0.0,
        };
    }
    (min_clearance, inverse_sum)
}

/// Calls `visit` with points along `geo` from the entry to the end, no more than `spacing` apart.
pub fn sample_points(geo: &PathGeometry, spacing: f32, mut visit: impl FnMut(V3)) {
    visit(geo.starts[0].p);
    for i in 0..geo.form.len() {
        let len = geo.lengths[i];
        let pieces = libm::ceilf(len / spacing).max(1.0) as u32;
        for k in 1..=pieces {
            let t = len * k as f32 / pieces as f32;
            visit(geo.starts[i].point_at(geo.form.kind(i), t, geo.radius));
        }
    }
}
