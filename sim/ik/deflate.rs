//! The general 6R elimination's known roots taken out before the eigenvalue iteration.
//!
//! Its determinant `det(C + B x + A x^2)` (24th degree in joint 3's half-angle tangent `x`) always
//! has the factor `(1 + x^2)^4`, a higher power for special geometry (six on a UR type): eight or
//! more of the 24 x 24 companion matrix's eigenvalues are `x = +-i`, never a solution. Their
//! eigenvectors `[v; i v]` (`P(i) v = 0`, `P(i) = C - A + i B`) span a real invariant subspace,
//! and it is the arm's, not the pose's: at `x = i` the right side's constant drops out (it
//! carries `1 + x^2`) and the null vectors annul the left side's `e^(i theta3)` part on every row,
//! whatever combination of rows the pose's elimination keeps. So an orthonormal basis of its
//! complement, found once per arm and tangent offset, reduces the companion to the block holding
//! the other eigenvalues (16 x 16 for a general arm): the Hessenberg reduction and the QR steps
//! on 16 rows instead of 24, and the multiple pairs at `+-i`, slow to converge, never iterated
//! on. Each pose checks that the subspace still is one (`P(i) v` at rounding); where not, the
//! caller iterates on the whole companion.

use super::eigen::Hessenberg;
use super::lines::leading_inverse;
use nalgebra::{Complex, DMatrix, SMatrix};

type Matrix12 = SMatrix<f64, 12, 12>;

/// Singular values of `P(i)` (relative to its largest) at or below this are its null space; the
/// others must be above [`RANK`], so that the split is clear.
const NULL: f64 = 1e-11;
const RANK: f64 = 1e-6;
/// Largest `|P(i) v| / |P(i)|` (Frobenius, `v` unit) at which the subspace still holds at a pose.
const HOLDS: f64 = 1e-10;

/// The complement of the `+-i` eigenvectors' subspace for one arm and tangent offset.
#[derive(Debug, Clone)]
pub(crate) struct Deflation {
    /// Real and imaginary parts of `P(i)`'s unit null vectors (12 x nullity: four for a general
    /// arm, more for special geometry, whose factor has a higher power).
    null_re: DMatrix<f64>,
    null_im: DMatrix<f64>,
    /// The orthonormal complement (24 x `24 - 2 nullity`), its top and bottom halves.
    top: DMatrix<f64>,
    bottom: DMatrix<f64>,
    /// `top^T bottom`: the block's part that does not depend on the pose.
    top_bottom: DMatrix<f64>,
}

impl Deflation {
    /// From the matrix quadratic of any pose of the arm at this offset; `None` when `P(i)` has no
    /// clear null space (the caller keeps the whole companion).
    pub(crate) fn of(c: &Matrix12, b: &Matrix12, a: &Matrix12) -> Option<Deflation> {
        let p = (c - a).zip_map(b, Complex::new);
        let svd = p.svd(false, true);
        let v_t = svd.v_t?;
        let mut order: Vec<usize> = (0..12).collect();
        order.sort_by(|&i, &j| svd.singular_values[i].total_cmp(&svd.singular_values[j]));
        let largest = svd.singular_values[order[11]];
        let nullity = order.iter().take_while(|&&i| svd.singular_values[i] <= NULL * largest).count();
        if !(largest > 0.0 && (1..12).contains(&nullity) && svd.singular_values[order[nullity]] > RANK * largest) {
            return None;
        }
        let (kept, size) = (2 * nullity, 24 - 2 * nullity);
        // `P v = 0` for `v` the conjugate of a row of `V^H`.
        let null = |k: usize, row: usize| v_t[(order[k], row)].conj();
        let null_re = DMatrix::from_fn(12, nullity, |row, k| null(k, row).re);
        let null_im = DMatrix::from_fn(12, nullity, |row, k| null(k, row).im);
        // The real invariant subspace: `[x; -y]` and `[y; x]` for each `v = x + i y`, then the
        // identity, so that a full QR's last columns are the complement.
        let spanning = DMatrix::from_fn(24, kept + 24, |row, col| match col {
            col if col < kept => {
                let (k, imaginary_part) = (col / 2, col % 2 == 1);
                match (row < 12, imaginary_part) {
                    (true, false) => null_re[(row, k)],
                    (false, false) => -null_im[(row - 12, k)],
                    (true, true) => null_im[(row, k)],
                    (false, true) => null_re[(row - 12, k)],
                }
            }
            _ => f64::from(u8::from(row == col - kept)),
        });
        let qr = spanning.qr();
        let r = qr.r();
        if (0..kept).any(|k| r[(k, k)].abs() < RANK) {
            return None;
        }
        let q = qr.q();
        let top = DMatrix::from_fn(12, size, |row, col| q[(row, kept + col)]);
        let bottom = DMatrix::from_fn(12, size, |row, col| q[(12 + row, kept + col)]);
        Some(Deflation {
            null_re,
            null_im,
            top_bottom: top.tr_mul(&bottom),
            top,
            bottom,
        })
    }

    /// The companion's eigenvalues other than the `+-i` ones, `(re, im)` in no particular order;
    /// `None` when the subspace does not hold at this pose, `a` is ill-conditioned (see
    /// [`leading_inverse`]) or the iteration does not converge.
    pub(crate) fn eigenvalues(&self, c: &Matrix12, b: &Matrix12, a: &Matrix12) -> Option<Vec<(f64, f64)>> {
        let d = c - a;
        let residual_re = d * &self.null_re - b * &self.null_im;
        let residual_im = d * &self.null_im + b * &self.null_re;
        let residual = (residual_re.norm_squared() + residual_im.norm_squared()).sqrt();
        // The null vectors are unit: their Frobenius norm is the square root of their count.
        let count = self.null_re.ncols() as f64;
        // False for NaN too.
        let holds = residual <= HOLDS * count.sqrt() * (d.norm_squared() + b.norm_squared()).sqrt();
        if !holds {
            return None;
        }
        let inverse = leading_inverse(a)?;
        // The companion `[[0, I], [-A^-1 C, -A^-1 B]]` on the complement `[top; bottom]`.
        let lower = -(inverse * (c * &self.top + b * &self.bottom));
        let block = &self.top_bottom + self.bottom.tr_mul(&lower);
        if !block.iter().all(|x| x.is_finite()) {
            return None;
        }
        let size = block.nrows();
        // Row-major for the iteration.
        let values: Vec<f64> = block.transpose().as_slice().to_vec();
        Hessenberg::new(size, values).eigenvalues(80 * 12)
    }
}
