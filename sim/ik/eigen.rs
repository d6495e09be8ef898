//! The eigenvalues alone of a real square matrix, for the all-solutions methods' companion
//! matrices: Householder reduction to upper Hessenberg form, then Francis double-shift QR steps
//! with deflation at negligible subdiagonals (the classical EISPACK `hqr` scheme), neither
//! accumulating the Schur vectors nalgebra's `Schur` computes, which cost more than the
//! eigenvalues here (issue 22's target: 20 us per pose for the general 6R elimination). The
//! steps are bounded: a matrix that does not converge gives `None`.

/// An `n x n` matrix, row-major, reduced in place.
pub(crate) struct Hessenberg {
    n: usize,
    a: Vec<f64>,
}

impl Hessenberg {
    /// `values` row-major, `n x n`.
    pub(crate) fn new(n: usize, values: Vec<f64>) -> Self {
        debug_assert_eq!(values.len(), n * n);
        let mut h = Hessenberg { n, a: values };
        h.reduce();
        h
    }

    fn at(&self, i: usize, j: usize) -> f64 {
        self.a[i * self.n + j]
    }

    fn set(&mut self, i: usize, j: usize, value: f64) {
        self.a[i * self.n + j] = value;
    }

    /// Householder reflections from the left and the right, column by column: similar, so the
    /// eigenvalues stay.
    fn reduce(&mut self) {
        let n = self.n;
        let (mut v, mut w) = (vec![0.0; n], vec![0.0; n]);
        for k in 0..n.saturating_sub(2) {
            let norm = (k + 1..n).map(|i| self.at(i, k).powi(2)).sum::<f64>().sqrt();
            if norm == 0.0 {
                continue;
            }
            let alpha = if self.at(k + 1, k) > 0.0 { -norm } else { norm };
            for (i, value) in v.iter_mut().enumerate().skip(k + 1) {
                *value = self.a[i * n + k];
            }
            v[k + 1] -= alpha;
            let length = (k + 1..n).map(|i| v[i] * v[i]).sum::<f64>().sqrt();
            if length == 0.0 {
                continue;
            }
            for value in &mut v[k + 1..n] {
                *value /= length;
            }
            // A <- (I - 2 v v^T) A over rows k + 1.., then A <- A (I - 2 v v^T); row by row, so
            // every inner loop runs along a row.
            w[k..].fill(0.0);
            for (i, &vi) in v.iter().enumerate().skip(k + 1) {
                let row = &self.a[i * n + k..i * n + n];
                for (wj, aij) in w[k..].iter_mut().zip(row) {
                    *wj += vi * aij;
                }
            }
            for (i, &vi) in v.iter().enumerate().skip(k + 1) {
                let row = &mut self.a[i * n + k..i * n + n];
                for (aij, wj) in row.iter_mut().zip(&w[k..]) {
                    *aij -= 2.0 * vi * wj;
                }
            }
            // Four rows at a time: each row's dot product keeps its own order of additions,
            // and the four chains overlap instead of waiting on one another.
            let tail = &v[k + 1..n];
            let mut groups = self.a.chunks_exact_mut(4 * n);
            for group in &mut groups {
                let (r0, rest) = group.split_at_mut(n);
                let (r1, rest) = rest.split_at_mut(n);
                let (r2, r3) = rest.split_at_mut(n);
                let (r0, r1, r2, r3) = (&mut r0[k + 1..], &mut r1[k + 1..], &mut r2[k + 1..], &mut r3[k + 1..]);
                let mut dots = [-0.0f64; 4];
                for ((((a0, a1), a2), a3), vj) in r0.iter().zip(r1.iter()).zip(r2.iter()).zip(r3.iter()).zip(tail) {
                    dots[0] += a0 * vj;
                    dots[1] += a1 * vj;
                    dots[2] += a2 * vj;
                    dots[3] += a3 * vj;
                }
                for (row, dot) in [r0, r1, r2, r3].into_iter().zip(dots) {
                    for (aij, vj) in row.iter_mut().zip(tail) {
                        *aij -= 2.0 * dot * vj;
                    }
                }
            }
            for row in groups.into_remainder().chunks_exact_mut(n) {
                let row = &mut row[k + 1..];
                let dot: f64 = row.iter().zip(tail).map(|(a, b)| a * b).sum();
                for (aij, vj) in row.iter_mut().zip(tail) {
                    *aij -= 2.0 * dot * vj;
                }
            }
            for i in k + 2..n {
                self.set(i, k, 0.0);
            }
        }
    }

    /// The eigenvalues as (real, imaginary) pairs, in no particular order; `None` when a block
    /// takes more than `max_steps` QR steps to split off.
    pub(crate) fn eigenvalues(mut self, max_steps: usize) -> Option<Vec<(f64, f64)>> {
        let n = self.n;
        let mut out = Vec::with_capacity(n);
        if n == 0 {
            return Some(out);
        }
        let scale: f64 = (0..n)
            .map(|i| (i.saturating_sub(1)..n).map(|j| self.at(i, j).abs()).sum::<f64>())
            .sum();
        // Shifts applied to the whole diagonal so far (the exceptional ones).
        let mut shifted = 0.0;
        let mut last = n as isize - 1;
        while last >= 0 {
            let nn = last as usize;
            let mut steps = 0;
            loop {
                // The lowest row whose subdiagonal is negligible bounds the active block.
                let mut l = nn;
                while l > 0 {
                    let mut s = self.at(l - 1, l - 1).abs() + self.at(l, l).abs();
                    if s == 0.0 {
                        s = scale;
                    }
                    if self.at(l, l - 1).abs() + s == s {
                        self.set(l, l - 1, 0.0);
                        break;
                    }
                    l -= 1;
                }
                let x = self.at(nn, nn);
                if l == nn {
                    out.push((x + shifted, 0.0));
                    last -= 1;
                    break;
                }
                let y = self.at(nn - 1, nn - 1);
                let w = self.at(nn, nn - 1) * self.at(nn - 1, nn);
                if l == nn - 1 {
                    // A 2 x 2 block: its eigenvalues in closed form.
                    let p = 0.5 * (y - x);
                    let q = p * p + w;
                    let root = q.abs().sqrt();
                    let base = x + shifted;
                    if q >= 0.0 {
                        let z = p + root.copysign(p);
                        let second = if z != 0.0 { base - w / z } else { base + z };
                        out.push((base + z, 0.0));
                        out.push((second, 0.0));
                    } else {
                        out.push((base + p, root));
                        out.push((base + p, -root));
                    }
                    last -= 2;
                    break;
                }
                if steps == max_steps {
                    return None;
                }
                let (mut x, mut y, mut w) = (x, y, w);
                if steps > 0 && steps % 10 == 0 {
                    // An exceptional shift breaks a cycle.
                    shifted += x;
                    for i in 0..=nn {
                        self.a[i * n + i] -= x;
                    }
                    let s = self.at(nn, nn - 1).abs() + self.at(nn - 1, nn - 2).abs();
                    x = 0.75 * s;
                    y = x;
                    w = -0.4375 * s * s;
                }
                steps += 1;
                self.francis_step(l, nn, x, y, w);
            }
        }
        Some(out)
    }

    /// One double-shift step on the active block `l..=nn`, shifts from the trailing 2 x 2 block
    /// (`x`, `y` its diagonal, `w` the product of its off-diagonal entries).
    fn francis_step(&mut self, l: usize, nn: usize, x: f64, y: f64, w: f64) {
        let n = self.n;
        // The start row: the lowest where the bulge's first column is negligible above.
        let mut m = nn - 2;
        let (mut p, mut q, mut r);
        loop {
            let z = self.at(m, m);
            let (rr, ss) = (x - z, y - z);
            p = (rr * ss - w) / self.at(m + 1, m) + self.at(m, m + 1);
            q = self.at(m + 1, m + 1) - z - rr - ss;
            r = self.at(m + 2, m + 1);
            let s = p.abs() + q.abs() + r.abs();
            p /= s;
            q /= s;
            r /= s;
            if m == l {
                break;
            }
            let u = self.at(m, m - 1).abs() * (q.abs() + r.abs());
            let v = p.abs() * (self.at(m - 1, m - 1).abs() + z.abs() + self.at(m + 1, m + 1).abs());
            if u + v == v {
                break;
            }
            m -= 1;
        }
        for i in m + 2..=nn {
            self.set(i, i - 2, 0.0);
            if i != m + 2 {
                self.set(i, i - 3, 0.0);
            }
        }
        for k in m..nn {
            let mut scale = 1.0;
            if k != m {
                p = self.at(k, k - 1);
                q = self.at(k + 1, k - 1);
                r = if k != nn - 1 { self.at(k + 2, k - 1) } else { 0.0 };
                scale = p.abs() + q.abs() + r.abs();
                if scale != 0.0 {
                    p /= scale;
                    q /= scale;
                    r /= scale;
                }
            }
            let s = (p * p + q * q + r * r).sqrt().copysign(p);
            if s == 0.0 {
                continue;
            }
            if k == m {
                if l != m {
                    let value = -self.at(k, k - 1);
                    self.set(k, k - 1, value);
                }
            } else {
                self.set(k, k - 1, -s * scale);
            }
            p += s;
            let (hx, hy, hz) = (p / s, q / s, r / s);
            let (q2, r2) = (q / p, r / p);
            let third = k != nn - 1;
            let (first, rest) = self.a[k * n..].split_at_mut(n);
            let (second, rest) = rest.split_at_mut(n);
            let (first, second) = (&mut first[k..=nn], &mut second[k..=nn]);
            if third {
                let third_row = &mut rest[k..=nn];
                for ((a0, a1), a2) in first.iter_mut().zip(second.iter_mut()).zip(third_row.iter_mut()) {
                    let dot = *a0 + q2 * *a1 + r2 * *a2;
                    *a2 -= dot * hz;
                    *a1 -= dot * hy;
                    *a0 -= dot * hx;
                }
            } else {
                for (a0, a1) in first.iter_mut().zip(second.iter_mut()) {
                    let dot = *a0 + q2 * *a1;
                    *a1 -= dot * hy;
                    *a0 -= dot * hx;
                }
            }
            let rows = self.a[l * n..(nn.min(k + 3) + 1) * n].chunks_exact_mut(n);
            if third {
                for row in rows {
                    let [a0, a1, a2] = &mut row[k..k + 3] else {
                        unreachable!("three columns")
                    };
                    let dot = hx * *a0 + hy * *a1 + hz * *a2;
                    *a2 -= dot * r2;
                    *a1 -= dot * q2;
                    *a0 -= dot;
                }
            } else {
                for row in rows {
                    let [a0, a1] = &mut row[k..k + 2] else {
                        unreachable!("two columns")
                    };
                    let dot = hx * *a0 + hy * *a1;
                    *a1 -= dot * q2;
                    *a0 -= dot;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;
    use rand::{Rng, SeedableRng};

    /// Against nalgebra's complex eigenvalues of random matrices (some with repeated and
    /// complex eigenvalues), matched one to one.
    #[test]
    fn the_eigenvalues_agree_with_nalgebras() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for trial in 0..200 {
            let n = [1, 2, 3, 5, 8, 16, 24][trial % 7];
            let values: Vec<f64> = (0..n * n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mine = Hessenberg::new(n, values.clone()).eigenvalues(80 * n).expect("converges");
            let theirs = DMatrix::from_row_slice(n, n, &values).complex_eigenvalues();
            assert_eq!(mine.len(), n);
            let mut used = vec![false; n];
            for (re, im) in &mine {
                let (best, distance) = theirs
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| !used[*i])
                    .map(|(i, z)| (i, (z.re - re).hypot(z.im - im)))
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .expect("one left");
                assert!(distance < 1e-8, "trial {trial}: ({re}, {im}) is {distance} from nalgebra's nearest");
                used[best] = true;
            }
        }
    }

    #[test]
    fn a_companion_matrix_gives_its_polynomials_roots() {
        // (x - 1)(x - 2)(x^2 + 1) = x^4 - 3x^3 + 3x^2 - 3x + 2.
        let values = vec![0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, -2.0, 3.0, -3.0, 3.0];
        let mut roots = Hessenberg::new(4, values).eigenvalues(320).expect("converges");
        roots.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let expected = [(0.0, -1.0), (0.0, 1.0), (1.0, 0.0), (2.0, 0.0)];
        for ((re, im), (er, ei)) in roots.iter().zip(expected) {
            assert!((re - er).abs() < 1e-10 && (im - ei).abs() < 1e-10, "{roots:?}");
        }
    }
}
