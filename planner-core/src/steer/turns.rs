//! The bevel turns a continuation may command. A turn under the dead band is not commanded at
//! all: below the shaft's torsional play it does not reach the tip, above it a controller that
//! turns by tenths of a degree at every reading only wears the driver. The solve's small turns
//! are rounded to the band's steps (none, or the band), and when neither rounding passes the
//! check the solve is run again with those turns held at the nearer step, the lengths and the
//! other turns free to make up for it.

use super::replan::{checked, ReplanInput, Replanned};
use crate::optim::problem::{Problem, Vars};
use crate::report::{SegmentPlan, Segments};

/// How far a held turn may move from its step (degrees): a box, not a point, so the SQP's
/// bound rows stay apart.
const HELD_SLACK_DEG: f32 = 0.2;

/// `deg`, or no turn at all when it is within `band` of a whole turn.
pub(super) fn dead_banded(deg: f32, band: f32) -> f32 {
    let off = libm::fmodf(libm::fabsf(deg), 360.0);
    if off < band || 360.0 - off < band {
        0.0
    } else {
        deg
    }
}

/// `deg`, or the nearest turn of at least `band` (on the same side) when it is a smaller turn
/// than that from a whole turn.
pub(super) fn widened_to_band(deg: f32, band: f32) -> f32 {
    let whole = libm::roundf(deg / 360.0) * 360.0;
    let off = deg - whole;
    if off == 0.0 || libm::fabsf(off) >= band {
        deg
    } else {
        whole + libm::copysignf(band, off)
    }
}

/// The side of a whole turn `deg` is on, and how far (degrees).
fn off_whole(deg: f32) -> f32 {
    deg - libm::roundf(deg / 360.0) * 360.0
}

/// The miss a continuation may predict: the target's tolerance, or half of what the smallest
/// turn the dead band allows would move the end, when that is more. Turning the bevel by θ
/// turns the whole continuation about the tip's heading, moving its end by θ times the end's
/// distance from that axis; a turn rounded to the band's steps (none, or the band) misses by at
/// most half a step.
pub(super) fn accepted_miss(input: &ReplanInput) -> f32 {
    let local = input.tip.r.transpose() * (input.target - input.tip.p);
    let off_axis = crate::fmath::sqrt(local.x * local.x + local.y * local.y);
    let step = input.dead_band_deg.to_radians() * off_axis;
    input.scenario.target.tolerance.max(0.5 * step)
}

/// `exact` as commanded, if it passes: its small turns left out, else widened to the band.
pub(super) fn commanded(
    input: &ReplanInput,
    exact: &[SegmentPlan],
    spent: &(u32, u32),
) -> Option<Replanned> {
    let mut banded = Segments::from_slice(exact).ok()?;
    let mut widened = banded.clone();
    for (b, w) in banded.iter_mut().zip(widened.iter_mut()) {
        b.bevel_deg = dead_banded(b.bevel_deg, input.dead_band_deg);
        w.bevel_deg = widened_to_band(w.bevel_deg, input.dead_band_deg);
    }
    checked(input, &banded, spent).or_else(|| {
        (widened != banded)
            .then(|| checked(input, &widened, spent))
            .flatten()
    })
}

/// The problem `p` with each turn of `exact` under the band held near the step it rounds to
/// (none, or the band on its side), and the solution `x` moved inside; `None` when `exact` has
/// no such turn.
pub(super) fn held<'a>(
    p: &Problem<'a>,
    x: &Vars,
    exact: &[SegmentPlan],
    band: f32,
) -> Option<(Problem<'a>, Vars)> {
    let (mut q, mut y, mut any) = (p.clone(), *x, false);
    for (i, seg) in exact.iter().enumerate() {
        let Some(k) = p.bevel_var(i) else {
            continue;
        };
        let off = off_whole(seg.bevel_deg);
        if off == 0.0 || libm::fabsf(off) >= band {
            continue;
        }
        any = true;
        // The step nearer to the solve's turn, and a slack on the side away from zero for the
        // band, so what the solve returns rounds to that step again.
        let (low, high) = if libm::fabsf(off) < 0.5 * band {
            (-HELD_SLACK_DEG, HELD_SLACK_DEG)
        } else if off > 0.0 {
            (band, band + HELD_SLACK_DEG)
        } else {
            (-band - HELD_SLACK_DEG, -band)
        };
        // The variable may hold the turn plus whole turns: the box moves with it.
        let base = y[k] - off.to_radians();
        q.lower[k] = base + low.to_radians();
        q.upper[k] = base + high.to_radians();
        y[k] = crate::fmath::clamp(y[k], q.lower[k], q.upper[k]);
    }
    any.then_some((q, y))
}
