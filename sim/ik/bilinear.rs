//! Every real common root of two equations in two angles, each a combination of
//! `{1, sin a, cos a} x {1, sin b, cos b}`: half-angle tangents make them quadratics in both,
//! and the Sylvester resultant in `x_a` (a 4 x 4 matrix quadratic in `x_b`) is an 8 x 8
//! companion eigenproblem. Each real root in `x_b` gives `x_a` from the two quadratics' common
//! root.

use super::lines::{half_angle, quadratic_roots};
use nalgebra::Matrix4;

/// Offsets of the half-angle tangents (rad): a root at `offset + pi` would be at infinity, so
/// they are angles no design chooses on purpose; `b` is retried at the others.
const OFFSET_A: f64 = 0.583_117_2;
pub(crate) const OFFSETS_B: [f64; 4] = [-1.193_406_1, 0.377_212_9, 2.441_730_5, -2.806_102_3];

/// The real common roots `(a, b)` of `equations` (coefficients indexed `fa * 3 + fb`), and
/// whether every root in `b` gave its `a` (false where the quadratics in `x_a` vanish for every
/// `x_a`, a continuum); `None` when the resultant's leading
/// matrix is singular at every offset tried (the equations share a factor, or are degenerate).
pub(crate) fn common_roots(equations: &[[f64; 9]; 2]) -> Option<(Vec<(f64, f64)>, bool)> {
    let (offset_b, roots, [c, b, a]) = roots(equations)?;
    let mut out = Vec::with_capacity(8);
    let mut resolved = true;
    for x_b in roots {
        let matrix = c + b * x_b + a * (x_b * x_b);
        let t_b = offset_b + 2.0 * x_b.atan();
        // Rows 0 and 2: (0, qa, qb, qc) of the two quadratics in x_a at this x_b.
        let (a1, b1, c1) = (matrix[(0, 1)], matrix[(0, 2)], matrix[(0, 3)]);
        let (a2, b2, c2) = (matrix[(2, 1)], matrix[(2, 2)], matrix[(2, 3)]);
        let denominator = b1 * a2 - b2 * a1;
        let scale = (a1.abs() + b1.abs() + c1.abs()) * (a2.abs() + b2.abs() + c2.abs());
        if denominator.abs() > 1e-9 * scale {
            let x_a = (c2 * a1 - c1 * a2) / denominator;
            out.push((OFFSET_A + 2.0 * x_a.atan(), t_b));
            continue;
        }
        // Both quadratics share both roots: solve the larger.
        let row = if matrix.row(0).norm() >= matrix.row(2).norm() { 0 } else { 2 };
        let (qa, qb, qc) = (matrix[(row, 1)], matrix[(row, 2)], matrix[(row, 3)]);
        if qa.abs() < 1e-14 {
            if qb.abs() > 1e-14 {
                out.push((OFFSET_A + 2.0 * (-qc / qb).atan(), t_b));
            } else if qc.abs() <= 1e-14 {
                // Every x_a: a continuum.
                resolved = false;
            }
            continue;
        }
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            continue;
        }
        let root = disc.sqrt();
        for x_a in [(-qb + root) / (2.0 * qa), (-qb - root) / (2.0 * qa)] {
            out.push((OFFSET_A + 2.0 * x_a.atan(), t_b));
        }
    }
    Some((out, resolved))
}

/// The offset of `b` used, the near-real roots in `x_b` and the resultant's coefficients.
fn roots(equations: &[[f64; 9]; 2]) -> Option<(f64, Vec<f64>, [Matrix4<f64>; 3])> {
    for offset_b in OFFSETS_B {
        let [c, b, a] = resultant(equations, offset_b);
        let Some(roots) = quadratic_roots(&c, &b, &a) else { continue };
        // A root near infinity is imprecise: another offset moves it.
        if roots.iter().any(|x| x.abs() > 50.0) && offset_b != OFFSETS_B[OFFSETS_B.len() - 1] {
            continue;
        }
        return Some((offset_b, roots, [c, b, a]));
    }
    None
}

/// The Sylvester matrix's coefficients of `x_b^0, x_b^1, x_b^2`: each quadratic in `x_a` times
/// `x_a` and times 1, against `(x_a^3, x_a^2, x_a, 1)`.
pub(crate) fn resultant(equations: &[[f64; 9]; 2], offset_b: f64) -> [Matrix4<f64>; 3] {
    let (ha, hb) = (half_angle(OFFSET_A), half_angle(offset_b));
    // poly[equation][power of x_a][power of x_b]
    let mut poly = [[[0.0; 3]; 3]; 2];
    for (e, coefficients) in equations.iter().enumerate() {
        for fa in 0..3 {
            for fb in 0..3 {
                let c = coefficients[fa * 3 + fb];
                for pa in 0..3 {
                    for pb in 0..3 {
                        poly[e][pa][pb] += c * ha[(fa, pa)] * hb[(fb, pb)];
                    }
                }
            }
        }
    }
    let mut out = [Matrix4::zeros(); 3];
    for (e, equation) in poly.iter().enumerate() {
        for shift in 0..2 {
            let row = 2 * e + shift;
            for (pa, by_b) in equation.iter().enumerate() {
                let column = 3 - (pa + shift);
                for (pb, value) in by_b.iter().enumerate() {
                    out[pb][(row, column)] = *value;
                }
            }
        }
    }
    out
}
