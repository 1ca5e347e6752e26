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

#[cfg(test)]
mod tests {
    use super::solve;

    /// `a x` for the leading `dim`-square block.
    fn product<const N: usize>(a: &[[f32; N]; N], x: &[f32; N], dim: usize) -> [f32; N] {
        let mut out = [0.0; N];
        for r in 0..dim {
            out[r] = (0..dim).map(|c| a[r][c] * x[c]).sum();
        }
        out
    }

    #[test]
    fn solves_a_three_by_three_system_with_a_known_solution() {
        // 2x + y - z = 8, -3x - y + 2z = -11, -2x + y + 2z = -3: x = 2, y = 3, z = -1.
        let mut a = [[2.0, 1.0, -1.0], [-3.0, -1.0, 2.0], [-2.0, 1.0, 2.0]];
        let mut b = [8.0, -11.0, -3.0];
        assert!(solve(&mut a, &mut b, 3));
        for (got, want) in b.iter().zip([2.0, 3.0, -1.0]) {
            assert!((got - want).abs() < 1e-5, "{b:?}");
        }
    }

    #[test]
    fn a_zero_on_the_diagonal_is_pivoted_away() {
        // Without a row exchange the first pivot is zero.
        let mut a = [[0.0, 1.0], [1.0, 0.0]];
        let mut b = [2.0, 3.0];
        assert!(solve(&mut a, &mut b, 2));
        assert_eq!(b, [3.0, 2.0]);
        assert_eq!(a[0], [1.0, 0.0]);
    }

    #[test]
    fn pivots_are_judged_against_their_own_rows_scale() {
        // Unscaled partial pivoting would keep row 0 (30 > 5.291), whose size is set by its
        // 591400; relative to their rows, row 1's 5.291 is the larger pivot. x = 10, y = 1.
        let a0 = [[30.0, 591_400.0], [5.291, -6.13]];
        let b0 = [591_700.0, 46.78];
        let (mut a, mut b) = (a0, b0);
        assert!(solve(&mut a, &mut b, 2));
        // The pivot row was moved to the top.
        assert_eq!(a[0], a0[1]);
        assert!(
            (b[0] - 10.0).abs() < 1e-3 && (b[1] - 1.0).abs() < 1e-6,
            "{b:?}"
        );
        let back = product(&a0, &b, 2);
        for (got, want) in back.iter().zip(b0) {
            assert!((got - want).abs() <= 1e-5 * want.abs(), "{back:?}");
        }
    }

    #[test]
    fn a_singular_system_is_refused() {
        // The second row is twice the first: elimination leaves a zero pivot.
        let mut a = [[1.0, 2.0], [2.0, 4.0]];
        let mut b = [1.0, 2.0];
        assert!(!solve(&mut a, &mut b, 2));
        // A zero row has no scale at all.
        let mut a = [[1.0, 2.0], [0.0, 0.0]];
        let mut b = [1.0, 0.0];
        assert!(!solve(&mut a, &mut b, 2));
    }

    #[test]
    fn an_ill_conditioned_system_is_refused() {
        // The rows differ by one f32 ulp of 1 (1.19e-7), below the relative pivot floor of 1e-6.
        let mut a = [[1.0, 1.0], [1.0, 1.0 + f32::EPSILON]];
        let mut b = [2.0, 2.0];
        assert!(!solve(&mut a, &mut b, 2));
        // A hundred times the floor is solved: x = (1, 1).
        let mut a = [[1.0, 1.0], [1.0, 1.0 + 1e-4]];
        let mut b = [2.0, 2.0 + 1e-4];
        assert!(solve(&mut a, &mut b, 2));
        assert!(
            (b[0] - 1.0).abs() < 1e-2 && (b[1] - 1.0).abs() < 1e-2,
            "{b:?}"
        );
    }

    #[test]
    fn a_solution_that_is_not_finite_is_refused() {
        let mut a = [[1.0, 0.0], [0.0, 1.0]];
        let mut b = [f32::INFINITY, 1.0];
        assert!(!solve(&mut a, &mut b, 2));
    }

    #[test]
    fn only_the_leading_block_is_read_and_written() {
        // Entries outside the leading 2 x 2 block are garbage the solve must not touch or read.
        let mut a = [[4.0, 2.0, f32::NAN], [2.0, 3.0, f32::NAN], [f32::NAN; 3]];
        let mut b = [10.0, 11.0, f32::NAN];
        assert!(solve(&mut a, &mut b, 2));
        // 4x + 2y = 10, 2x + 3y = 11: x = 1, y = 3.
        assert!(
            (b[0] - 1.0).abs() < 1e-6 && (b[1] - 3.0).abs() < 1e-6,
            "{b:?}"
        );
        assert!(b[2].is_nan() && a[2].iter().all(|v| v.is_nan()));
    }
}
