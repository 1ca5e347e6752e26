//! Warm starts for a replan beyond the remaining segments: the same path with a degree of
//! freedom more, and a leading line turned away from the sphere it drifted towards.

use super::continuation::ReplanInput;
use crate::model::form::SegmentKind;
use crate::model::kinematics::V3;
use crate::report::{SegmentPlan, Segments};

/// Variants of the remaining segments with one degree of freedom more, each the same path but
/// for a millimetre: a short line before the first arc, a short line in the middle of the
/// longest arc, or that arc split in two (a bevel rotation more between the halves); a lone line
/// gets an arc aimed at the target before it. A line moves the rest of the path forward along
/// the heading where it is inserted, which no length or bevel of a fixed-curvature arc can do.
pub(super) fn variants(remaining: &[SegmentPlan], aim_deg: f32) -> [Option<Segments>; 3] {
    let line = SegmentPlan {
        kind: SegmentKind::Line,
        length: 1.0,
        bevel_deg: 0.0,
    };
    let longest = (0..remaining.len())
        .filter(|&i| remaining[i].kind == SegmentKind::Arc)
        .max_by(|&a, &b| remaining[a].length.total_cmp(&remaining[b].length));
    let Some(k) = longest else {
        let mut out = Segments::new();
        let arc = SegmentPlan {
            kind: SegmentKind::Arc,
            length: 1.0,
            bevel_deg: aim_deg,
        };
        let ok = out.push(arc).is_ok() && remaining.iter().all(|s| out.push(*s).is_ok());
        return [ok.then_some(out), None, None];
    };
    let build = |at: usize, middle: &[SegmentPlan]| -> Option<Segments> {
        let mut out = Segments::new();
        for (i, seg) in remaining.iter().enumerate() {
            if i == at {
                for m in middle {
                    out.push(*m).ok()?;
                }
            } else {
                out.push(*seg).ok()?;
            }
        }
        Some(out)
    };
    let arc = remaining[k];
    let half = SegmentPlan {
        length: 0.5 * arc.length,
        ..arc
    };
    let second = SegmentPlan {
        bevel_deg: 0.0,
        ..half
    };
    let first_arc = (0..remaining.len()).find(|&i| remaining[i].kind == SegmentKind::Arc);
    let before = first_arc.and_then(|i| {
        let preceded = i > 0 && remaining[i - 1].kind == SegmentKind::Line;
        (!preceded)
            .then(|| build(i, &[line, remaining[i]]))
            .flatten()
    });
    [
        before,
        build(k, &[half, line, second]),
        build(k, &[half, second]),
    ]
}

/// A remaining path that starts with a line, turned away from the sphere nearest that line by
/// a short arc before it: a line goes on along the heading it starts with, so a tip that
/// drifted towards a sphere beside it has no start near its path clear of the sphere.
pub(super) fn turned_away(input: &ReplanInput, remaining: &[SegmentPlan]) -> Option<Segments> {
    let line = remaining.first().filter(|s| s.kind == SegmentKind::Line)?;
    let tip = &input.tip;
    let mut nearest: Option<(f32, V3)> = None;
    for ob in &input.scenario.obstacles {
        let local = tip.r.transpose() * (V3::new(ob.center[0], ob.center[1], ob.center[2]) - tip.p);
        if !(local.z > 0.0 && local.z < line.length + ob.radius) {
            continue;
        }
        let gap = crate::fmath::sqrt(local.x * local.x + local.y * local.y) - ob.radius;
        if nearest.is_none_or(|(g, _)| gap < g) {
            nearest = Some((gap, local));
        }
    }
    let (_, local) = nearest?;
    let away_deg = crate::fmath::atan2(local.x, -local.y).to_degrees();
    let mut out = Segments::new();
    out.push(SegmentPlan {
        kind: SegmentKind::Arc,
        length: TURN_AWAY_MM,
        bevel_deg: away_deg,
    })
    .ok()?;
    for s in remaining {
        out.push(*s).ok()?;
    }
    Some(out)
}

/// The arc that turns a leading line away from a sphere (mm): a degree of heading at the
/// needle's curvature.
const TURN_AWAY_MM: f32 = 1.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::kinematics::Frame;
    use crate::model::scenario::{Obstacle, Scenario, Workspace};
    use crate::steer::attempt::attempt;
    use crate::steer::continuation::{form_of, sub_scenario};

    /// A tip whose line now passes a sphere closer than the margin: no start along the line
    /// is clear of it, the line turned away is, and the replan finds a continuation from it
    /// that keeps the margin and reaches the target.
    #[test]
    fn a_line_that_drifted_towards_a_sphere_is_turned_away() {
        let mut scenario = Scenario::paper();
        scenario.options.workspace = Workspace::Space;
        scenario.obstacles.clear();
        // A line along +z, then an arc bending towards +x; the line passes 0.2 mm from the
        // sphere's surface, on its -y side.
        let _ = scenario.obstacles.push(Obstacle {
            center: [0.0, 5.2, 20.0],
            radius: 5.0,
        });
        let tip = Frame {
            p: V3::new(0.0, 0.0, 0.0),
            r: nalgebra::Matrix3::identity(),
        };
        let r = scenario.needle.curvature_radius;
        let mut remaining = Segments::new();
        for (kind, length, bevel_deg) in [
            (SegmentKind::Line, 40.0, 0.0),
            (SegmentKind::Arc, 30.0, 90.0),
        ] {
            let _ = remaining.push(SegmentPlan {
                kind,
                length,
                bevel_deg,
            });
        }
        let end = tip
            .advanced(SegmentKind::Line, 40.0, r)
            .rolled(90f32.to_radians())
            .advanced(SegmentKind::Arc, 30.0, r);
        let input = ReplanInput {
            scenario: &scenario,
            tip,
            target: end.p,
            radius: r,
            twist_deg: 0.0,
            iterations: 10,
            margin: 0.4,
            inserted_mm: 0.0,
            dead_band_deg: 2.0,
            arc_duty: 1.0,
            spend_reserve: true,
            turn_early: false,
        };
        let start = turned_away(&input, &remaining).expect("a start turned away");
        assert_eq!(start.len(), 3);
        // The sphere is to +y: the bevel turns the bend towards -y.
        assert!((start[0].bevel_deg.abs() - 180.0).abs() < 1e-3, "{start:?}");
        // From the line as it is, the solve has no start clear of the margin; turned away, it
        // finds a continuation that keeps it and reaches the target.
        let mut sub = sub_scenario(&input);
        let mut spent = (0, 0);
        let straight = form_of(&remaining).unwrap();
        assert!(attempt(&input, &mut sub, straight, &remaining, &mut spent).is_none());
        let form = form_of(&start).unwrap();
        let found = attempt(&input, &mut sub, form, &start, &mut spent).expect("a continuation");
        assert!(
            found.prediction.min_clearance > 0.4,
            "{:?}",
            found.prediction
        );
        assert!(found.prediction.target_error <= scenario.target.tolerance);
        // Nothing to turn from where no sphere is beside the line.
        let mut open = scenario.clone();
        open.obstacles.clear();
        let input = ReplanInput {
            scenario: &open,
            ..input
        };
        assert!(turned_away(&input, &remaining).is_none());
    }
}
