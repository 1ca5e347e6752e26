//! The bevel turns a continuation may command. A turn under the dead band is not commanded at
//! all: below the shaft's torsional play it does not reach the tip, above it a controller that
//! turns by tenths of a degree at every reading only wears the driver. The solve's small turns
//! are rounded to the band's steps (none, or the band on their side). (Solving again with such
//! turns held at the nearer step was tried: it changed no figure of the families, and its code
//! did not fit the 128 KiB part.)

use super::continuation::{checked, ReplanInput, Replanned};
use crate::report::{SegmentPlan, Segments};

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_turn_becomes_none_or_the_band_on_its_side() {
        assert_eq!(dead_banded(0.5, 2.0), 0.0);
        assert_eq!(dead_banded(359.5, 2.0), 0.0);
        assert_eq!(dead_banded(3.0, 2.0), 3.0);
        assert_eq!(widened_to_band(0.5, 2.0), 2.0);
        assert_eq!(widened_to_band(-0.5, 2.0), -2.0);
        assert_eq!(widened_to_band(359.5, 2.0), 358.0);
        assert_eq!(widened_to_band(-3.0, 2.0), -3.0);
        assert_eq!(widened_to_band(0.0, 2.0), 0.0);
    }
}
