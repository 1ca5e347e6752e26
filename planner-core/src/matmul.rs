//! Matrix products for the estimator and the spread propagation, kept out of line.
//!
//! nalgebra unrolls a fixed-size product completely: the Kalman update alone took 9 KiB of the
//! firmware's flash (whose budget is 128 KiB), the spread's 6×6 sums 22 KiB more. These loops
//! take the sizes at run time, so one copy serves every shape, and they sum in nalgebra's order
//! (`k` ascending, from the first product), so the results are the same bit for bit.

use nalgebra::SMatrix;

/// `a * b`.
pub(crate) fn mul<const R: usize, const K: usize, const C: usize>(
    a: &SMatrix<f32, R, K>,
    b: &SMatrix<f32, K, C>,
) -> SMatrix<f32, R, C> {
    let mut out = SMatrix::<f32, R, C>::zeros();
    mul_into(a.as_slice(), R, K, b.as_slice(), C, out.as_mut_slice());
    out
}

/// `a * b * aᵀ`, as nalgebra evaluates it (left to right).
pub(crate) fn sandwich<const R: usize, const K: usize>(
    a: &SMatrix<f32, R, K>,
    b: &SMatrix<f32, K, K>,
) -> SMatrix<f32, R, R> {
    mul(&mul(a, b), &a.transpose())
}

/// `m += here · thereᵀ · variance`, element by element as nalgebra's
/// `m += here * there.transpose() * variance` rounds it.
#[inline(never)]
pub(crate) fn add_outer<const N: usize>(
    m: &mut SMatrix<f32, N, N>,
    here: &SMatrix<f32, N, 1>,
    there: &SMatrix<f32, N, 1>,
    variance: f32,
) {
    for (j, col) in m.as_mut_slice().chunks_exact_mut(N).enumerate() {
        for (i, o) in col.iter_mut().enumerate() {
            *o += here[i] * there[j] * variance;
        }
    }
}

/// Column-major `out (rows × cols) = a (rows × inner) · b (inner × cols)`: each column of `out`
/// gathered as `a`'s columns scaled by that column of `b`, `k` ascending, which adds every
/// element's products in the same order as a dot product would (the same bits), over contiguous
/// columns (no strided reads, no bounds checks in the inner loop).
#[inline(never)]
fn mul_into(a: &[f32], rows: usize, inner: usize, b: &[f32], cols: usize, out: &mut [f32]) {
    for (out_col, b_col) in out
        .chunks_exact_mut(rows)
        .zip(b.chunks_exact(inner))
        .take(cols)
    {
        let mut a_cols = a.chunks_exact(rows).zip(b_col);
        if let Some((a0, b0)) = a_cols.next() {
            for (o, x) in out_col.iter_mut().zip(a0) {
                *o = x * b0;
            }
        }
        for (a_col, bk) in a_cols {
            for (o, x) in out_col.iter_mut().zip(a_col) {
                *o += x * bk;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same bits as nalgebra's own product, on values whose sums round.
    #[test]
    fn products_equal_nalgebra_bit_for_bit() {
        let a = SMatrix::<f32, 3, 7>::from_fn(|i, j| ((i * 7 + j) as f32 * 0.37).sin() * 1e3);
        let b = SMatrix::<f32, 7, 7>::from_fn(|i, j| ((i * 7 + j) as f32 * 1.91).cos() / 3.0);
        assert_eq!(mul(&a, &b).as_slice(), (a * b).as_slice());
        assert_eq!(
            sandwich(&a, &b).as_slice(),
            (a * b * a.transpose()).as_slice()
        );
        let c = SMatrix::<f32, 7, 3>::from_fn(|i, j| (i as f32 - j as f32 * 2.5) * 0.1);
        assert_eq!(mul(&b, &c).as_slice(), (b * c).as_slice());
        let (h, t) = (b.column(2).into_owned(), b.column(5).into_owned());
        let mut m = b;
        add_outer(&mut m, &h, &t, 0.37);
        assert_eq!(m.as_slice(), (b + h * t.transpose() * 0.37).as_slice());
    }
}
