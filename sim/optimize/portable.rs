//! `sin`, `cos`, `exp` and `atan2` written with IEEE additions, multiplications, divisions and
//! exact bit operations alone, the same operations in the same order as `fused.cu`'s `pg_*`
//! functions, so that the fused objective rounds identically on the CPU and on a CUDA GPU (whose
//! libdevice and the system's libm round differently by an ulp here and there, which 200 Adam
//! steps through the objective's kinks grow into a different design). The algorithms are
//! musl's (from FreeBSD's msun): Cody-Waite reduction by pi/2 in three rounds with minimax
//! kernels on [-pi/4, pi/4], exp by reduction by ln 2 and a rational kernel, atan by reduction
//! to four intervals; within 1 ulp of the true value on the ranges used (tested against the
//! standard library).

/// 2/pi and pi/2 in three parts of 33 bits each with their tails (fdlibm's `__rem_pio2`).
const INVPIO2: u64 = 0x3FE4_5F30_6DC9_C883;
const PIO2: [(u64, u64); 3] = [
    (0x3FF9_21FB_5440_0000, 0x3DD0_B461_1A62_6331),
    (0x3DD0_B461_1A60_0000, 0x3BA3_198A_2E03_7073),
    (0x3BA3_198A_2E00_0000, 0x397B_839A_2520_49C1),
];
const S: [u64; 6] = [
    0xBFC5_5555_5555_5549,
    0x3F81_1111_1110_F8A6,
    0xBF2A_01A0_19C1_61D5,
    0x3EC7_1DE3_57B1_FE7D,
    0xBE5A_E5E6_8A2B_9CEB,
    0x3DE5_D93A_5ACF_D57C,
];
const C: [u64; 6] = [
    0x3FA5_5555_5555_554C,
    0xBF56_C16C_16C1_5177,
    0x3EFA_01A0_19CB_1590,
    0xBE92_7E4F_809C_52AD,
    0x3E21_EE9E_BDB4_B1C4,
    0xBDA8_FAE9_BE88_38D4,
];

fn f(bits: u64) -> f64 {
    f64::from_bits(bits)
}

/// `x` reduced by pi/2: the quadrant and the remainder as a head and a tail.
fn rem_pio2(x: f64) -> (i64, f64, f64) {
    let n = (x * f(INVPIO2)).round();
    let mut r = x - n * f(PIO2[0].0);
    let mut w = n * f(PIO2[0].1);
    for &(part, tail) in &PIO2[1..] {
        let t = r;
        w = n * f(part);
        r = t - w;
        w = n * f(tail) - ((t - r) - w);
    }
    let y0 = r - w;
    let y1 = (r - y0) - w;
    (n as i64, y0, y1)
}

/// sin(x + y) for |x + y| <= pi/4, `y` the tail of `x`.
fn kernel_sin(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = (f(S[1]) + z * (f(S[2]) + z * f(S[3]))) + (z * w) * (f(S[4]) + z * f(S[5]));
    let v = z * x;
    x - ((z * (0.5 * y - v * r) - y) - v * f(S[0]))
}

/// cos(x + y) for |x + y| <= pi/4.
fn kernel_cos(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = z * (f(C[0]) + z * (f(C[1]) + z * f(C[2]))) + (w * w) * (f(C[3]) + z * (f(C[4]) + z * f(C[5])));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + (z * r - x * y))
}

/// sin(x).
pub(crate) fn sin(x: f64) -> f64 {
    let (n, y0, y1) = rem_pio2(x);
    match n & 3 {
        0 => kernel_sin(y0, y1),
        1 => kernel_cos(y0, y1),
        2 => -kernel_sin(y0, y1),
        _ => -kernel_cos(y0, y1),
    }
}

/// cos(x).
pub(crate) fn cos(x: f64) -> f64 {
    let (n, y0, y1) = rem_pio2(x);
    match n & 3 {
        0 => kernel_cos(y0, y1),
        1 => -kernel_sin(y0, y1),
        2 => -kernel_cos(y0, y1),
        _ => kernel_sin(y0, y1),
    }
}

const LN2_HI: u64 = 0x3FE6_2E42_FEE0_0000;
const LN2_LO: u64 = 0x3DEA_39EF_3579_3C76;
const INVLN2: u64 = 0x3FF7_1547_652B_82FE;
const P: [u64; 5] = [
    0x3FC5_5555_5555_553E,
    0xBF66_C16C_16BE_BD93,
    0x3F11_566A_AF25_DE2C,
    0xBEBB_BD41_C5D2_6BF1,
    0x3E66_3769_72BE_A4D0,
];

/// `y` times 2^`n` (musl's `scalbn`).
fn scale(mut y: f64, mut n: i64) -> f64 {
    let (up, down) = (f(0x7FE0_0000_0000_0000), f(0x0360_0000_0000_0000));
    if n > 1023 {
        y *= up;
        n -= 1023;
        if n > 1023 {
            y *= up;
            n = (n - 1023).min(1023);
        }
    } else if n < -1022 {
        y *= down;
        n += 1022 - 53;
        if n < -1022 {
            y *= down;
            n = (n + 1022 - 53).max(-1022);
        }
    }
    y * f(((0x3FF + n) as u64) << 52)
}

/// e^x.
pub(crate) fn exp(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    if x > 709.782_712_893_384 {
        return f64::INFINITY;
    }
    if x < -745.133_219_101_941_1 {
        return 0.0;
    }
    let k = (x * f(INVLN2)).round();
    let hi = x - k * f(LN2_HI);
    let lo = k * f(LN2_LO);
    let r = hi - lo;
    let rr = r * r;
    let c = r - rr * (f(P[0]) + rr * (f(P[1]) + rr * (f(P[2]) + rr * (f(P[3]) + rr * f(P[4])))));
    let y = 1.0 + (((r * c) / (2.0 - c) - lo) + hi);
    scale(y, k as i64)
}

const ATAN_HI: [u64; 4] = [
    0x3FDD_AC67_0561_BB4F,
    0x3FE9_21FB_5444_2D18,
    0x3FEF_730B_D281_F69B,
    0x3FF9_21FB_5444_2D18,
];
const ATAN_LO: [u64; 4] = [
    0x3C7A_2B7F_222F_65E2,
    0x3C81_A626_3314_5C07,
    0x3C70_0788_7AF0_CBBD,
    0x3C91_A626_3314_5C07,
];
const AT: [u64; 11] = [
    0x3FD5_5555_5555_550D,
    0xBFC9_9999_9998_EBC4,
    0x3FC2_4924_9200_83FF,
    0xBFBC_71C6_FE23_1671,
    0x3FB7_45CD_C54C_206E,
    0xBFB3_B0F2_AF74_9A6D,
    0x3FB1_0D66_A0D0_3D51,
    0xBFAD_DE2D_52DE_FD9A,
    0x3FA9_7B4B_2476_0DEB,
    0xBFA2_B444_2C6A_6C2F,
    0x3F90_AD3A_E322_DA11,
];

/// atan(x) for x >= 0.
fn atan_of_positive(x: f64) -> f64 {
    if x >= f(0x4410_0000_0000_0000) {
        return f(ATAN_HI[3]);
    }
    let (id, x) = if x < 0.4375 {
        (None, x)
    } else if x < 0.6875 {
        (Some(0), (2.0 * x - 1.0) / (2.0 + x))
    } else if x < 1.1875 {
        (Some(1), (x - 1.0) / (x + 1.0))
    } else if x < 2.4375 {
        (Some(2), (x - 1.5) / (1.0 + 1.5 * x))
    } else {
        (Some(3), -1.0 / x)
    };
    let z = x * x;
    let w = z * z;
    let a = |i: usize| f(AT[i]);
    let s1 = z * (a(0) + w * (a(2) + w * (a(4) + w * (a(6) + w * (a(8) + w * a(10))))));
    let s2 = w * (a(1) + w * (a(3) + w * (a(5) + w * (a(7) + w * a(9)))));
    match id {
        None => x - x * (s1 + s2),
        Some(id) => f(ATAN_HI[id]) - ((x * (s1 + s2) - f(ATAN_LO[id])) - x),
    }
}

const PI: u64 = 0x4009_21FB_5444_2D18;
const PI_LO: u64 = 0x3CA1_A626_3314_5C07;

/// atan2(y, x), the angle of (x, y) in (-pi, pi].
pub(crate) fn atan2(y: f64, x: f64) -> f64 {
    if x.is_nan() || y.is_nan() {
        return x + y;
    }
    if y < 0.0 {
        return -atan2(-y, x);
    }
    if x == 0.0 {
        return if y == 0.0 { 0.0 } else { f(ATAN_HI[3]) };
    }
    let z = atan_of_positive((y / x).abs());
    if x > 0.0 {
        z
    } else {
        f(PI) - (z - f(PI_LO))
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};

    /// Distance in units in the last place.
    fn ulps(a: f64, b: f64) -> u64 {
        if a == b {
            return 0;
        }
        let key = |x: f64| {
            let bits = x.to_bits() as i64;
            if bits < 0 {
                i64::MIN - bits
            } else {
                bits
            }
        };
        key(a).abs_diff(key(b))
    }

    #[test]
    fn within_an_ulp_or_two_of_the_standard_library() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut worst = [0u64; 4];
        for i in 0..200_000 {
            // Joint angles (and beyond), the collision cost's exponents, the pose angle's arguments.
            let q: f64 = rng.random_range(-40.0..40.0) * if i % 10 == 0 { 1e-6 } else { 1.0 };
            let e: f64 = rng.random_range(-30.0..30.0);
            let (y, x): (f64, f64) = (rng.random_range(0.0..1.0), rng.random_range(-1.0..1.0));
            for (k, (ours, theirs)) in [
                (super::sin(q), q.sin()),
                (super::cos(q), q.cos()),
                (super::exp(e), e.exp()),
                (super::atan2(y, x), y.atan2(x)),
            ]
            .into_iter()
            .enumerate()
            {
                let apart = ulps(ours, theirs);
                // Near a zero of sin or cos the result is tiny and its ulp too: count against
                // the argument's ulp there.
                let apart = if theirs.abs() < 1e-3 {
                    apart.min(ulps(ours + 1.0, theirs + 1.0))
                } else {
                    apart
                };
                worst[k] = worst[k].max(apart);
            }
        }
        assert!(worst.iter().all(|&w| w <= 2), "sin, cos, exp, atan2 worst ulps: {worst:?}");
        for (x, y) in [(0.0, 1.0), (-1.0, 0.0), (1.0, 0.0), (-1.0, 1e-300), (1e-300, 1.0), (-0.5, 0.5)] {
            assert!(ulps(super::atan2(y, x), f64::atan2(y, x)) <= 1, "atan2({y}, {x})");
        }
        assert_eq!(super::exp(0.0), 1.0);
        assert_eq!(super::exp(-800.0), 0.0);
        assert_eq!(super::sin(0.0), 0.0);
        assert_eq!(super::cos(0.0), 1.0);
    }
}
