//! Cholesky factorisation and solve of a symmetric positive definite 6x6 matrix, written out for
//! the fixed size: the damped least-squares step solves one per iteration, and nalgebra's generic
//! column views cost more than the arithmetic at 6x6.
//!
//! The operations and their order are nalgebra's `Cholesky::new` and `Cholesky::solve` (0.35),
//! so every result is the same to the last bit (tested against it): a faster solver must not move
//! a single IK answer.

use nalgebra::{Matrix6, Vector6};

/// The lower Cholesky factor `L` (`M = L L^T`), column by column: `columns[c][r] = L[(r, c)]`.
pub(super) struct Cholesky6 {
    columns: [[f64; 6]; 6],
}

impl Cholesky6 {
    /// The factor of `matrix`, reading its lower triangle only; `None` when it is not positive
    /// definite (a pivot zero, negative or NaN).
    pub(super) fn new(matrix: &Matrix6<f64>) -> Option<Self> {
        let mut a = [[0.0; 6]; 6];
        for (c, column) in a.iter_mut().enumerate() {
            for (r, value) in column.iter_mut().enumerate().skip(c) {
                *value = matrix[(r, c)];
            }
        }
        for j in 0..6 {
            for k in 0..j {
                let factor = -a[k][j];
                let (left, right) = a.split_at_mut(j);
                let (column_k, column_j) = (&left[k], &mut right[0]);
                for i in j..6 {
                    column_j[i] += factor * column_k[i];
                }
            }
            let diag = a[j][j];
            // nalgebra's `try_sqrt`: defined for `diag >= 0`; a zero pivot fails too.
            if diag <= 0.0 || diag.is_nan() {
                return None;
            }
            let denom = diag.sqrt();
            a[j][j] = denom;
            for value in &mut a[j][j + 1..] {
                *value /= denom;
            }
        }
        Some(Self { columns: a })
    }

    /// The solution `x` of `M x = b`.
    pub(super) fn solve(&self, b: &Vector6<f64>) -> Vector6<f64> {
        let l = &self.columns;
        let mut x = *b;
        // L y = b, forward.
        for i in 0..6 {
            let coeff = x[i] / l[i][i];
            x[i] = coeff;
            for r in i + 1..6 {
                x[r] += -coeff * l[i][r];
            }
        }
        // L^T x = y, backward; the dot product summed from zero in row order, as nalgebra's.
        for i in (0..6).rev() {
            let mut dot = 0.0;
            for r in i + 1..6 {
                dot += l[i][r] * x[r];
            }
            x[i] = (x[i] - dot) / l[i][i];
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn same_bits_as_nalgebra() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut factored = 0;
        for sample in 0..20_000 {
            // Damped normal matrices as the solver builds them, from well conditioned to nearly
            // singular, and some indefinite ones.
            let damping: f64 = 10f64.powf(rng.random_range(-9.0..1.0));
            let mut m = Matrix6::<f64>::identity() * (damping * damping);
            let columns = rng.random_range(1..=7);
            for _ in 0..columns {
                let v = Vector6::from_fn(|_, _| rng.random_range(-1.0..1.0));
                m += v * v.transpose();
            }
            if sample % 10 == 0 {
                m[(3, 3)] = -m[(3, 3)];
            }
            let b = Vector6::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let ours = Cholesky6::new(&m);
            let theirs = m.cholesky();
            assert_eq!(ours.is_some(), theirs.is_some(), "sample {sample}: {m}");
            if let (Some(ours), Some(theirs)) = (ours, theirs) {
                factored += 1;
                let (x, y) = (ours.solve(&b), theirs.solve(&b));
                for (p, q) in x.iter().zip(y.iter()) {
                    assert_eq!(p.to_bits(), q.to_bits(), "sample {sample}: {x} vs {y}");
                }
            }
        }
        assert!(factored > 15_000, "{factored}");
    }
}
