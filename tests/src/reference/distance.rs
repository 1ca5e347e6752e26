//! Exact shortest distance from a point to a line segment or a circular arc (f64, closed form).

use super::frame::{Frame, V3};
use core::f64::consts::TAU;

/// Distance from `c` to the line segment of length `len` leaving `f` along its heading.
pub fn to_line(f: &Frame, len: f64, c: V3) -> f64 {
    let t = (c - f.p).dot(f.e3).clamp(0.0, len.max(0.0));
    (f.p + f.e3 * t - c).norm()
}

/// Distance from `c` to the arc of length `len` and radius `rho` leaving `f` (turning to `e2`).
///
/// Points of the arc are `m + rho (-cos t e2 + sin t e3)`, `t` in `[0, len / rho]`, with `m` the
/// circle's centre. The squared distance is `n^2 + r^2 + rho^2 - 2 rho r cos(t - t0)` (`n` the
/// offset along e1, `r` and `t0` the polar form of the in-plane offset), so it falls towards
/// `t0` on either side: the nearest point is at `t0` if the arc covers it, else an end.
pub fn to_arc(f: &Frame, len: f64, rho: f64, c: V3) -> f64 {
    let m = f.p + f.e2 * rho;
    let q = c - m;
    let (qx, qy, qn) = (q.dot(f.e2), q.dot(f.e3), q.dot(f.e1));
    let r = qx.hypot(qy);
    let sweep = len / rho;
    if r > 0.0 {
        let mut t0 = qy.atan2(-qx);
        if t0 < 0.0 {
            t0 += TAU;
        }
        if t0 <= sweep {
            return qn.hypot(r - rho);
        }
    }
    let start = (f.p - c).norm();
    let end = (f.arc(len, rho).p - c).norm();
    start.min(end)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::frame::{entry_basis, insertion};
    use needle_sim::random::{seeded, Draw};

    #[test]
    fn exact_distances_match_dense_sampling() {
        let mut rng = seeded(7);
        for _ in 0..400 {
            let b = entry_basis(V3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 1.0));
            let f = insertion(
                V3::new(rng.range(-5.0, 5.0), 0.0, 1.0),
                &b,
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            )
            .roll(rng.range(-3.2, 3.2));
            let rho = rng.range(10.0, 100.0);
            let len = rng.range(0.0, 2.0 * core::f64::consts::PI * rho);
            let c = V3::new(
                rng.range(-150.0, 150.0),
                rng.range(-150.0, 150.0),
                rng.range(-150.0, 150.0),
            );
            let n = 20_000;
            let (mut arc_min, mut line_min) = (f64::INFINITY, f64::INFINITY);
            for k in 0..=n {
                let t = len * f64::from(k) / f64::from(n);
                arc_min = arc_min.min((f.arc(t, rho).p - c).norm());
                line_min = line_min.min((f.line(t).p - c).norm());
            }
            // Sampling only overestimates, by at most half a step.
            let step = len / f64::from(n);
            let a = to_arc(&f, len, rho, c);
            assert!(
                a <= arc_min + 1e-9 && a >= arc_min - step,
                "arc {a} vs {arc_min}"
            );
            let l = to_line(&f, len, c);
            assert!(
                l <= line_min + 1e-9 && l >= line_min - step,
                "line {l} vs {line_min}"
            );
        }
    }
}
