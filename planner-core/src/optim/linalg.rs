//! The one dense linear solve of the optimiser: Gaussian elimination with scaled partial
//! pivoting on fixed arrays (Nocedal & Wright, Algorithm 16.3's KKT systems, and the restoration's
//! small normal equations).

/// Solves the leading `dim`-square system of `a x = b` (both overwritten; `b` becomes x);
/// false when a pivot vanishes or x is not finite.
pub(crate) fn solve<const N: usize>(a: &mut [[f32; N]; N], b: &mut [f32; N], dim: usize) -> bool {
    // Scaled partial pivoting: the N rows mix scales (Hessian entries in the 10^5 next to unit
    // bound rows), so a pivot is judged against its own row's size, not the matrix's.
    let mut inv_scale = [0.0f32; N];
    for (s, row) in inv_scale.iter_mut().zip(a.iter()).take(dim) {
        let size = row
            .iter()
            .take(dim)
            .fold(0.0f32, |m, v| crate::fmath::max(m, libm::fabsf(*v)));
        if !(size > 0.0) {
            return false;
        }
        *s = 1.0 / size;
    }
    for col in 0..dim {
        let mut piv = col;
        let mut best = 0.0f32;
        for r in col..dim {
            let rel = libm::fabsf(a[r][col]) * inv_scale[r];
            if rel > best {
                best = rel;
                piv = r;
            }
        }
        if !(best > 1e-6) {
            return false;
        }
        if piv != col {
            // Only columns from `col` on are read again (the rest is eliminated).
            for c in col..dim {
                let t = a[col][c];
                a[col][c] = a[piv][c];
                a[piv][c] = t;
            }
            b.swap(col, piv);
            inv_scale.swap(col, piv);
        }
        for r in col + 1..dim {
            let f = a[r][col] / a[col][col];
            if f != 0.0 {
                for c in col..dim {
                    a[r][c] -= f * a[col][c];
                }
                b[r] -= f * b[col];
            }
        }
    }
    // Back substitution in place: x[c] for c > r is already in b[c].
    for r in (0..dim).rev() {
        let mut s = b[r];
        for c in r + 1..dim {
            s -= a[r][c] * b[c];
        }
        b[r] = s / a[r][r];
    }
    b[..dim].iter().all(|v| v.is_finite())
}
