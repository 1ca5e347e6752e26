//! Exact Euclidean distance transforms on voxel grids (Felzenszwalb and Huttenlocher,
//! "Distance transforms of sampled functions", Theory of Computing 2012: one pass per axis of
//! the lower envelope of parabolas), each axis with its own spacing: exact for grids whose axes
//! are orthogonal, as scanners' are.

/// Stands for "infinitely far" in the squared distances (finite, so differences stay numbers).
pub const FAR: f64 = 1e20;

/// The squared distances, along one line of samples `spacing` apart, to the nearest sample of
/// `f` (squared distances already), written into `out`. `v` and `z` are scratch of `f.len()`
/// and `f.len() + 1`.
fn transform_line(f: &[f64], spacing: f64, out: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    let x = |q: usize| q as f64 * spacing;
    for q in 1..n {
        loop {
            let p = v[k];
            let s = ((f[q] + x(q) * x(q)) - (f[p] + x(p) * x(p))) / (2.0 * (x(q) - x(p)));
            // z[0] is minus infinity: k never falls below 0.
            if s <= z[k] {
                k -= 1;
                continue;
            }
            k += 1;
            v[k] = q;
            z[k] = s;
            z[k + 1] = f64::INFINITY;
            break;
        }
    }
    let mut k = 0usize;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < x(q) {
            k += 1;
        }
        let d = x(q) - x(v[k]);
        *o = d * d + f[v[k]];
    }
}

/// The squared distance (mm²) from every cell centre of an `n` grid (i fastest) to the nearest
/// cell centre for which `seed` holds; [`FAR`] or more where no cell is a seed.
pub fn squared_edt(n: [usize; 3], spacing: [f64; 3], seed: impl Fn(usize) -> bool) -> Vec<f64> {
    let total = n[0] * n[1] * n[2];
    let mut d: Vec<f64> = (0..total)
        .map(|c| if seed(c) { 0.0 } else { FAR })
        .collect();
    let longest = n.iter().copied().max().unwrap_or(0);
    let (mut line, mut out) = (vec![0f64; longest], vec![0f64; longest]);
    let (mut v, mut z) = (vec![0usize; longest], vec![0f64; longest + 1]);
    let stride = [1, n[0], n[0] * n[1]];
    for axis in 0..3 {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let len = n[axis];
        for p in 0..n[a] {
            for q in 0..n[b] {
                let base = p * stride[a] + q * stride[b];
                for (t, l) in line[..len].iter_mut().enumerate() {
                    *l = d[base + t * stride[axis]];
                }
                transform_line(&line[..len], spacing[axis], &mut out[..len], &mut v, &mut z);
                for (t, o) in out[..len].iter().enumerate() {
                    d[base + t * stride[axis]] = *o;
                }
            }
        }
    }
    d
}
