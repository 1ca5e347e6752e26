//! The check's prediction: a continuation's motor steps executed on the nominal needle from the
//! estimated tip, its end measured against the target and its path against every obstacle.

use crate::execute::nominal::execute_from;
use crate::execute::schedule::Step;
use crate::model::broad::{worth_a_tree, Broad, Set};
use crate::model::clearance::closest;
use crate::model::form::SegmentKind;
use crate::model::kinematics::{Frame, V3};
use crate::model::scenario::{Scenario, Workspace, MAX_OBSTACLES};

/// Spacing of the sampled clearance check across a plane scenario's cylinders (mm).
pub(super) const PLANE_SPACING: f32 = 0.25;

/// What executing a continuation's steps on the nominal needle from the estimated tip gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// Distance from the predicted end to the estimated target (mm).
    pub target_error: f32,
    /// Smallest predicted clearance to any obstacle surface (mm; infinite without obstacles).
    pub min_clearance: f32,
    /// The predicted end frame.
    pub end: Frame,
}

/// Executes `steps` from `tip` with arc radius `radius` and measures the end against `target` and
/// the clearance to every obstacle, as the simulated tissue counts it: exact to spheres in 3-D;
/// in a plane scenario to the circles' cylinders across the plane, from points `PLANE_SPACING`
/// apart less half that spacing (no point of the path is farther from a sample). With many
/// spheres ([`worth_a_tree`]), a tree built here measures only those near the path.
pub fn predict(
    scenario: &Scenario,
    tip: &Frame,
    steps: &[Step],
    radius: f32,
    target: V3,
) -> Prediction {
    let broad = worth_a_tree(scenario.obstacles.len()).then(|| Broad::new(&scenario.obstacles));
    predict_with(scenario, broad.as_ref(), tip, steps, radius, target)
}

/// [`predict`] with the tree over the scenario's spheres (`None`: every sphere is measured),
/// for a caller that predicts many times in one scenario: the same answer bit for bit.
pub fn predict_with(
    scenario: &Scenario,
    broad: Option<&Broad>,
    tip: &Frame,
    steps: &[Step],
    radius: f32,
    target: V3,
) -> Prediction {
    measured(scenario, broad, tip, steps, radius, target, None)
}

/// [`predict`] for the check, which refuses a continuation whose end is farther than `miss`
/// from `target` or whose clearance is at most `floor`: `None` as soon as either is known,
/// without measuring the rest of the path; otherwise the same prediction, bit for bit. Why: most
/// continuations a replan tries are refused, and measuring each whole path made a reading that
/// tried a dozen cost 1.9 M instructions on the device (docs/firmware.md).
pub fn predict_accepted(
    scenario: &Scenario,
    tip: &Frame,
    steps: &[Step],
    radius: f32,
    target: V3,
    (miss, floor): (f32, f32),
) -> Option<Prediction> {
    // The end alone costs a frame per step; the clearance costs points along the whole path.
    let end = execute_from(*tip, steps, radius, |_, _, _, _| {});
    let gap = end.p - target;
    if !(crate::fmath::sqrt(gap.dot(&gap)) <= miss) {
        return None;
    }
    let broad = worth_a_tree(scenario.obstacles.len()).then(|| Broad::new(&scenario.obstacles));
    let p = measured(
        scenario,
        broad.as_ref(),
        tip,
        steps,
        radius,
        target,
        Some(floor),
    );
    (p.min_clearance > floor).then_some(p)
}

/// Sample points between two looks at whether the check's refusal is already known (a look
/// costs about as much as a point).
const REFUSAL_EVERY: u32 = 16;

/// [`predict_with`], stopping once a clearance at most `floor` is found (the prediction then
/// has a clearance at most `floor`, and is otherwise incomplete).
fn measured(
    scenario: &Scenario,
    broad: Option<&Broad>,
    tip: &Frame,
    steps: &[Step],
    radius: f32,
    target: V3,
    floor: Option<f32>,
) -> Prediction {
    let plane = scenario.options.workspace == Workspace::PlaneYz;
    let below = |d: f32| floor.is_some_and(|f| d <= f);
    let mut min_clearance = f32::INFINITY;
    let end = execute_from(*tip, steps, radius, |start, kind, length, radius| {
        if below(min_clearance) {
            return;
        }
        if plane && !scenario.obstacles.is_empty() {
            // Each sample point serves every obstacle (drawing the points was most of a
            // reading's cost when done per obstacle; the same points, so the same bits).
            let pieces =
                crate::fmath::clamp(libm::ceilf(length / PLANE_SPACING), 1.0, 4096.0) as u32;
            let half = 0.5 * length / pieces as f32;
            // The least squared distance to each axis: the root is correctly rounded, so
            // monotone, and the root of the least is the least of the roots, bit for bit (one
            // root per obstacle and segment instead of one per point).
            let mut least = [f32::INFINITY; MAX_OBSTACLES];
            let clearance = |least: &[f32; MAX_OBSTACLES]| {
                let obstacles = least.iter().zip(&scenario.obstacles);
                obstacles.fold(f32::INFINITY, |c, (l, ob)| {
                    crate::fmath::min(c, crate::fmath::sqrt(*l) - ob.radius - half)
                })
            };
            for k in 0..=pieces {
                let q = start.point_at(kind, length * k as f32 / pieces as f32, radius);
                for (l, ob) in least.iter_mut().zip(&scenario.obstacles) {
                    let (dy, dz) = (q.y - ob.center[1], q.z - ob.center[2]);
                    *l = crate::fmath::min(*l, dy * dy + dz * dz);
                }
                // A clearance so far at most the floor stays so (the rest can only lower it).
                if floor.is_some() && k % REFUSAL_EVERY == 0 && below(clearance(&least)) {
                    break;
                }
            }
            min_clearance = crate::fmath::min(min_clearance, clearance(&least));
        } else if !plane {
            let segment = Piece {
                start,
                kind,
                length,
                radius,
            };
            min_clearance = nearest(scenario, broad, &segment, min_clearance);
        }
    });
    let miss = end.p - target;
    Prediction {
        target_error: crate::fmath::sqrt(miss.dot(&miss)),
        min_clearance,
        end,
    }
}

/// The first reach a segment's nearest sphere is looked for within when none is known yet (mm;
/// it grows fourfold, [`REACH_GROWTHS`] times, before every sphere is measured).
const FIRST_REACH_MM: f32 = 8.0;

/// Times the reach grows.
const REACH_GROWTHS: usize = 6;

/// One segment of a predicted path.
struct Piece<'a> {
    start: &'a Frame,
    kind: SegmentKind,
    length: f32,
    radius: f32,
}

/// The smaller of `least` and the clearance of `piece` to the nearest sphere. With a tree, only
/// the spheres it finds within the reach are measured: `least` itself once it is known (a
/// sphere farther than it cannot lower it), else a reach that grows until a sphere lies within.
fn nearest(scenario: &Scenario, broad: Option<&Broad>, piece: &Piece, least: f32) -> f32 {
    let obstacles = &scenario.obstacles;
    let among = |set: &Set, mut least: f32| {
        for ob in set.iter().filter_map(|o| obstacles.get(o)) {
            let c = V3::new(ob.center[0], ob.center[1], ob.center[2]);
            let d = closest(piece.start, piece.kind, piece.length, piece.radius, &c);
            least = crate::fmath::min(least, d.distance - ob.radius);
        }
        least
    };
    // The distance to a line costs less than a look-up in the tree.
    let Some(broad) = broad.filter(|_| piece.kind == SegmentKind::Arc) else {
        return among(&Set::all(obstacles.len()), least);
    };
    let (mut reach, growths) = if least.is_finite() {
        (least.max(0.0), 1)
    } else {
        (FIRST_REACH_MM, REACH_GROWTHS)
    };
    for _ in 0..growths {
        let mut near = Set::default();
        let p = piece;
        broad.near_segment(
            obstacles, p.start, p.kind, p.length, p.radius, reach, &mut near,
        );
        let found = among(&near, least);
        // Every sphere left out is at least `reach` away.
        if found < reach || least.is_finite() {
            return found;
        }
        reach *= 4.0;
    }
    among(&Set::all(obstacles.len()), least)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::nominal::posture_frame;
    use crate::execute::schedule::{schedule, Op};

    /// Continuations from tips along the paper's plan, out of its plane and rolled: an arc, a
    /// turn and a spun line, of lengths drawn from a fixed sequence.
    fn continuations(scenario: &Scenario) -> impl Iterator<Item = (Frame, [Step; 3])> + '_ {
        let best = crate::plan(scenario).unwrap().best().unwrap().clone();
        let start = posture_frame(scenario, &schedule(scenario, &best).unwrap());
        let r = scenario.needle.curvature_radius;
        let step = |op| Step {
            op,
            duration_s: 1.0,
        };
        (0..400u32).map(move |i| {
            let x = |k: u32| ((i * 7919 + k * 104_729) % 1000) as f32 / 1000.0;
            let tip = start
                .advanced(SegmentKind::Arc, 60.0 * x(1), r)
                .rolled(6.3 * x(2));
            let steps = [
                step(Op::Insert {
                    length_mm: 5.0 + 60.0 * x(3),
                }),
                step(Op::Rotate {
                    angle_deg: 360.0 * x(4) - 180.0,
                }),
                step(Op::InsertSpin {
                    length_mm: 40.0 * x(5),
                    turns: 2,
                }),
            ];
            (tip, steps)
        })
    }

    /// The check's prediction refuses exactly what the whole prediction refuses and, where it
    /// accepts, is the whole prediction bit for bit: in the paper's plane (cylinders, sampled)
    /// and among its obstacles as spheres (3-D), at floors and misses around what each
    /// continuation comes to.
    #[test]
    fn the_checks_prediction_is_the_whole_one_or_refused() {
        let mut counts = [0u32; 2];
        for workspace in [Workspace::PlaneYz, Workspace::Space] {
            let mut scenario = Scenario::paper();
            scenario.options.workspace = workspace;
            let t = scenario.target.position;
            let target = V3::new(t[0], t[1], t[2]);
            let r = scenario.needle.curvature_radius;
            for (tip, steps) in continuations(&scenario) {
                let whole = predict(&scenario, &tip, &steps, r, target);
                for (dm, df) in [
                    (-0.5, -0.5),
                    (0.5, -0.5),
                    (-0.5, 0.5),
                    (0.5, 0.5),
                    (0.0, 0.0),
                    (0.0, -1e-3),
                ] {
                    let (miss, floor) = (whole.target_error + dm, whole.min_clearance + df);
                    let limits = (miss, floor);
                    let checked = predict_accepted(&scenario, &tip, &steps, r, target, limits);
                    let sound = whole.target_error <= miss && whole.min_clearance > floor;
                    assert_eq!(checked, sound.then_some(whole), "{workspace:?} {tip:?}");
                    counts[usize::from(sound)] += 1;
                }
            }
        }
        // Both outcomes are exercised, many times.
        assert!(counts.iter().all(|&n| n > 500), "{counts:?}");
    }
}
