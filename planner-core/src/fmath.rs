//! Single-precision elementary functions computed in f32 only.
//!
//! `libm`'s `sinf`/`cosf` evaluate their kernels in f64, which the Cortex-M4F (a
//! single-precision FPU) emulates in software: two thirds of the device's planning time went
//! there. These are Cody–Waite range reduction plus Cephes minimax polynomials (a few ulp), in
//! plain f32 arithmetic, so the host and the device compute the same bits.
//!
//! `libm::atan2f` is pure f32; the own `atan2` stays because it is not slower on the device:
//! with `libm::atan2f` the paper plan took 40.54 M instructions and the 3-D example 327.1 M,
//! against 41.41 M and 319.4 M with this one (`needle device-bench --json`, 2026-12-01, the
//! plans differ slightly), and keeping it keeps every plan bit for bit.

// The one module that may call libm's kernels (clippy.toml bans them everywhere else): `sqrt`
// reaches the FPU's root through `libm::sqrtf` on the hosts, and the tests compare with libm.
#![allow(clippy::disallowed_methods)]

use core::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

// pi/2 split so that k * PIO2_1 is exact for the k the planner meets.
const PIO2_1: f32 = 1.570_312_5;
const PIO2_2: f32 = 4.837_513e-4;
const PIO2_3: f32 = 7.549_79e-8;

/// The greater of `x` and `y`, the other one if either is NaN: the operations of `libm`'s
/// `fmaxf` (what `f32::max` calls on the Cortex-M4F, whose FPU has no max instruction), inline.
#[inline(always)]
pub fn max(x: f32, y: f32) -> f32 {
    if x.is_nan() || x < y {
        y
    } else {
        x
    }
}

/// The lesser of `x` and `y`, the other one if either is NaN (`libm`'s `fminf`, inline).
#[inline(always)]
pub fn min(x: f32, y: f32) -> f32 {
    if y.is_nan() || x < y {
        x
    } else {
        y
    }
}

/// `x` limited to `[lo, hi]`: the comparisons of `f32::clamp`, without its panic when a bound is
/// NaN or `lo > hi` (that panic also pulled float formatting into the firmware: 17 KiB).
#[inline(always)]
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    let mut x = x;
    if x < lo {
        x = lo;
    }
    if x > hi {
        x = hi;
    }
    x
}

/// sin and cos of `x` (radians). NaN and infinities give NaN.
pub fn sincos(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    let (k, quadrant) = round(x * (2.0 / PI));
    let r = ((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3;
    let z = r * r;
    let s = r + r * z * ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1);
    let c = 1.0 - 0.5 * z + z * z * ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2);
    match quadrant & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// sin of `x`.
pub fn sin(x: f32) -> f32 {
    sincos(x).0
}

/// cos of `x`.
pub fn cos(x: f32) -> f32 {
    sincos(x).1
}

/// `x` rounded half away from zero without libm (truncating x ± 0.5), and as an integer (the
/// cast saturates: only for |x| far beyond any angle here).
fn round(x: f32) -> (f32, i32) {
    let t = if x >= 0.0 { x + 0.5 } else { x - 0.5 };
    if t.abs() >= 8_388_608.0 {
        (t, t as i32)
    } else {
        let k = t as i32;
        (k as f32, k)
    }
}

/// atan of `x` for x >= 0.
fn atan_pos(x: f32) -> f32 {
    let (base, t) = if x > 2.414_213_6 {
        (FRAC_PI_2, -1.0 / x)
    } else if x > 0.414_213_57 {
        (FRAC_PI_4, (x - 1.0) / (x + 1.0))
    } else {
        (0.0, x)
    };
    let z = t * t;
    base + ((((8.053_744_5e-2 * z - 1.387_768_5e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1)
        * z
        * t
        + t)
}

/// atan of `x`.
pub fn atan(x: f32) -> f32 {
    if x.is_nan() {
        return f32::NAN;
    }
    if x < 0.0 {
        -atan_pos(-x)
    } else {
        atan_pos(x)
    }
}

/// The angle of the point (x, y) in (-pi, pi], as `atan2(y, x)`.
// Inlined on the host (1.2 % fewer instructions per plan); the firmware keeps one copy (inlined
// there it cost 4.7 KiB of flash for 1.3 % fewer instructions).
#[cfg_attr(not(target_os = "none"), inline)]
pub fn atan2(y: f32, x: f32) -> f32 {
    if x.is_nan() || y.is_nan() {
        return f32::NAN;
    }
    if x == 0.0 {
        return if y > 0.0 {
            FRAC_PI_2
        } else if y < 0.0 {
            -FRAC_PI_2
        } else {
            0.0
        };
    }
    if x.is_infinite() || y.is_infinite() {
        // Only the directions matter: map each infinite coordinate to ±1 and the finite one to 0.
        let unit = |v: f32| if v.is_infinite() { v.signum() } else { 0.0 };
        let (ys, xs) = (unit(y), unit(x));
        return if xs == 0.0 {
            ys * FRAC_PI_2
        } else {
            atan2(ys, xs)
        };
    }
    let a = atan(y / x);
    if x > 0.0 {
        a
    } else if y >= 0.0 {
        a + PI
    } else {
        a - PI
    }
}

/// Square root, correctly rounded (IEEE 754's `sqrt`), so the same bits on every target: the
/// FPU's instruction where safe `no_std` Rust reaches it (x86_64 and aarch64, through `libm`),
/// [`sqrt_soft`] elsewhere. The Cortex-M4F's `vsqrt` is out of reach (`f32::sqrt` needs `std`,
/// `libm` has no Arm routine and its generic one cost a tenth of the device's plan, inline
/// assembly needs `unsafe`). A test compares the two over every float.
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
    {
        libm::sqrtf(x)
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        sqrt_soft(x)
    }
}

/// The correctly rounded square root in f32 and integer arithmetic: an estimate within an ulp,
/// then moved to the rounded root by an exact integer test. On the host it runs in the
/// tests only (which compare it with the FPU's root).
#[cfg_attr(any(target_arch = "x86_64", target_arch = "aarch64"), allow(dead_code))]
pub fn sqrt_soft(x: f32) -> f32 {
    // One test for the common case (positive, finite, normal): the special cases and the scaling
    // of subnormals stay off its path.
    if (1e-30..f32::INFINITY).contains(&x) {
        return sqrt_normal(x);
    }
    if x > 0.0 && x < 1e-30 {
        // Subnormal or tiny: scaled by 2^100 into the normal range, both scalings exact.
        return sqrt_normal(x * f32::from_bits(227 << 23)) * f32::from_bits(77 << 23);
    }
    // 0 -> 0 (-0 -> -0), +inf -> inf, negative or NaN -> NaN.
    if x == 0.0 || x == f32::INFINITY {
        x
    } else {
        f32::NAN
    }
}

/// [`sqrt_soft`] of `x` in [1e-30, infinity).
#[cfg_attr(any(target_arch = "x86_64", target_arch = "aarch64"), allow(dead_code))]
fn sqrt_normal(x: f32) -> f32 {
    let mut y = f32::from_bits(0x5f37_5a86 - (x.to_bits() >> 1));
    // Two Newton steps for 1/sqrt and one for the root leave it within an ulp (a third step
    // would not: the rounding of the last one dominates).
    for _ in 0..2 {
        y *= 1.5 - 0.5 * x * y * y;
    }
    let s = x * y;
    rounded_root(x, s + 0.5 * y * (x - s * s))
}

/// The float next to `s` (positive, normal, within an ulp of sqrt(x)) that is sqrt(x) rounded to
/// nearest. With s = m 2^e (m the 24-bit significand) and x = mx 2^ex, s is that float when
/// sqrt(x) lies between the midpoints (m -+ 1/2) 2^e, that is when (2m - 1)^2 < 4x / 2^2e <
/// (2m + 1)^2, compared exactly in integers (4x / 2^2e = mx 2^k) through one square: with
/// d = 4x / 2^2e - 4m^2, s is the root when -4m + 1 < d < 4m + 1; below a power of two the lower
/// midpoint is m - 1/4 (d > -2m). Never equal: the left side is even, the squares odd.
#[cfg_attr(any(target_arch = "x86_64", target_arch = "aarch64"), allow(dead_code))]
fn rounded_root(x: f32, s: f32) -> f32 {
    let xb = x.to_bits();
    let sb = s.to_bits();
    let k = (xb >> 23) as i32 + 152 - 2 * ((sb >> 23) as i32);
    if !(0..=30).contains(&k) {
        return s;
    }
    let mx = (xb & 0x007f_ffff) | 0x0080_0000;
    let m = (sb & 0x007f_ffff) | 0x0080_0000;
    // Both terms are near 2^50 but, s being within an ulp or two, |d| < 8m (2^27): their low 32
    // bits give it exactly, with 32-bit integer operations only (the device has no 64-bit ones).
    let d = (mx << k).wrapping_sub((4 * m).wrapping_mul(m)) as i32;
    let m = m as i32;
    let lower = if m == 0x0080_0000 { -2 * m } else { -4 * m };
    // One move suffices: the test over every float checks it.
    if d <= lower {
        f32::from_bits(sb - 1)
    } else if d > 4 * m + 1 {
        f32::from_bits(sb + 1)
    } else {
        s
    }
}

/// `a` wrapped into [0, 2 pi).
pub fn wrap_positive(a: f32) -> f32 {
    if !a.is_finite() {
        return f32::NAN;
    }
    let tau = core::f32::consts::TAU;
    let mut r = a - tau * ((a / tau) as i32) as f32;
    if r < 0.0 {
        r += tau;
    }
    if r >= tau {
        r -= tau;
    }
    r
}

/// asin of `x` in [-1, 1] (clamped).
pub fn asin(x: f32) -> f32 {
    let x = clamp(x, -1.0, 1.0);
    atan2(x, sqrt((1.0 - x) * (1.0 + x)))
}

/// acos of `x` in [-1, 1] (clamped).
pub fn acos(x: f32) -> f32 {
    let x = clamp(x, -1.0, 1.0);
    atan2(sqrt((1.0 - x) * (1.0 + x)), x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_match_f64_to_a_few_ulp() {
        let mut worst = 0.0f64;
        for i in -20_000..=20_000 {
            let x = i as f32 * 1.7e-3;
            let (s, c) = sincos(x);
            worst = worst.max((s as f64 - (x as f64).sin()).abs());
            worst = worst.max((c as f64 - (x as f64).cos()).abs());
        }
        assert!(worst < 3e-7, "{worst}");
    }

    #[test]
    fn atan2_matches_f64_in_every_quadrant() {
        let mut worst = 0.0f64;
        for i in -300..=300 {
            for j in -300..=300 {
                let (y, x) = (i as f32 * 0.37, j as f32 * 0.41);
                let want = (y as f64).atan2(x as f64);
                worst = worst.max((atan2(y, x) as f64 - want).abs());
            }
        }
        assert!(worst < 5e-7, "{worst}");
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert!(atan2(f32::NAN, 1.0).is_nan());
        assert!(atan2(1.0, f32::INFINITY).abs() < 1e-6);
    }

    /// sqrt(x) correctly rounded, by another route: f64's root rounded to f32 (53 bits are more
    /// than twice 24 plus two, so the double rounding is exact).
    fn rounded(x: f32) -> f32 {
        libm::sqrt(f64::from(x)) as f32
    }

    fn check_soft_root(bits: impl Iterator<Item = u32>) -> u64 {
        let mut n = 0;
        for b in bits {
            let x = f32::from_bits(b);
            let (got, want) = (sqrt_soft(x), rounded(x));
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "{x:e}: {got:e}, not {want:e}"
            );
            n += 1;
        }
        n
    }

    #[test]
    fn soft_sqrt_is_the_correctly_rounded_root() {
        // Every 61st positive float, subnormals included, and every float near the powers of two
        // (where the spacing of the roots changes) and the scaling threshold.
        assert!(check_soft_root((1..0x7f80_0000u32).step_by(61)) > 34_000_000);
        for e in 1..255u32 {
            let p = e << 23;
            check_soft_root(p.saturating_sub(300)..(p + 300).min(0x7f80_0000));
        }
        let edge = 1e-30f32.to_bits();
        check_soft_root(edge - 5000..edge + 5000);
        assert_eq!(sqrt_soft(0.0).to_bits(), 0);
        assert_eq!(sqrt_soft(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(sqrt_soft(f32::INFINITY), f32::INFINITY);
        for x in [-1.0, f32::NAN, f32::NEG_INFINITY, -1e-40] {
            assert!(sqrt_soft(x).is_nan());
        }
        // On the host `sqrt` is the FPU's: the same bits.
        for b in (1..0x7f80_0000u32).step_by(9973) {
            let x = f32::from_bits(b);
            assert_eq!(sqrt(x).to_bits(), sqrt_soft(x).to_bits());
        }
    }

    /// Every positive float (2^31 of them; 18 s in release here):
    /// `cargo test --release -p planner-core --lib -- --ignored every_float`.
    #[test]
    #[ignore]
    fn soft_sqrt_is_the_correctly_rounded_root_of_every_float() {
        assert_eq!(check_soft_root(1..0x7f80_0000u32), 0x7f7f_ffff);
    }

    #[test]
    fn wrap_positive_wraps() {
        assert!((wrap_positive(-0.5) - (core::f32::consts::TAU - 0.5)).abs() < 1e-6);
        assert!((wrap_positive(7.0) - (7.0 - core::f32::consts::TAU)).abs() < 1e-6);
    }

    #[test]
    fn inverse_functions() {
        for i in -100..=100 {
            let x = i as f32 / 100.0;
            assert!((asin(x) as f64 - (x as f64).asin()).abs() < 1e-6);
            assert!((acos(x) as f64 - (x as f64).acos()).abs() < 1e-6);
        }
        assert!(sin(f32::INFINITY).is_nan());
    }
}
