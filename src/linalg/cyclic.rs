//! Cyclic tridiagonal systems (loops) in O(n): Sherman–Morrison on top of Thomas.
//!
//! A loop's matrix is tridiagonal plus the two corner entries that couple its last
//! edge to its first. Writing `A = T + u vᵀ`, with `T` tridiagonal, costs two Thomas
//! solves (`T y = b`, `T z = u`) and one correction.

use super::SingularPivot;
use super::tridiagonal::TridiagonalFactor;

/// A factored cyclic tridiagonal matrix, to solve many right-hand sides cheaply.
#[derive(Clone, Debug, Default)]
pub struct CyclicFactor {
    inner: TridiagonalFactor,
    diagonal: Vec<f64>,
    correction: Vec<f64>,
    beta_over_gamma: f64,
    denominator: f64,
}

impl CyclicFactor {
    /// Factor `A` (n ≥ 3; rows as in [`solve_cyclic_tridiagonal`]).
    pub fn factor(
        &mut self,
        lower: &[f64],
        diagonal: &[f64],
        upper: &[f64],
    ) -> Result<(), SingularPivot> {
        let n = diagonal.len();
        assert!(n >= 3, "a cyclic system needs at least 3 unknowns");
        let (alpha, beta) = (upper[n - 1], lower[0]); // A[n−1][0], A[0][n−1]
        let gamma = -diagonal[0];
        self.diagonal.clear();
        self.diagonal.extend_from_slice(diagonal);
        self.diagonal[0] -= gamma;
        self.diagonal[n - 1] -= alpha * beta / gamma;
        self.inner.factor(lower, &self.diagonal, upper)?;
        // z = T⁻¹ u with u = (γ, 0, …, 0, α).
        self.correction.clear();
        self.correction.resize(n, 0.0);
        self.correction[0] = gamma;
        self.correction[n - 1] = alpha;
        self.inner.solve(&mut self.correction);
        self.beta_over_gamma = beta / gamma;
        self.denominator = 1.0 + self.correction[0] + self.beta_over_gamma * self.correction[n - 1];
        if !(self.denominator.is_finite() && self.denominator != 0.0) {
            return Err(SingularPivot { row: n - 1 });
        }
        Ok(())
    }

    /// Solve `A x = rhs` in place.
    pub fn solve(&self, rhs: &mut [f64]) {
        self.solve_many(rhs, 1);
    }

    /// Solve `A X = B` in place for `k` right-hand sides stored row by row.
    pub fn solve_many(&self, columns: &mut [f64], k: usize) {
        let n = self.inner.len();
        self.inner.solve_many(columns, k);
        for c in 0..k {
            let factor =
                (columns[c] + self.beta_over_gamma * columns[(n - 1) * k + c]) / self.denominator;
            for (i, z) in self.correction.iter().enumerate() {
                columns[i * k + c] -= factor * z;
            }
        }
    }
}

/// Solve `A x = rhs` for cyclic tridiagonal `A` (n ≥ 3), overwriting `rhs` with `x`.
///
/// Row `i` is `lower[i] x[i−1] + diagonal[i] x[i] + upper[i] x[i+1]` with indices
/// modulo `n`: `lower[0]` multiplies `x[n−1]` and `upper[n−1]` multiplies `x[0]`.
/// `factor` is reusable storage; it holds the factorization afterwards.
pub fn solve_cyclic_tridiagonal(
    lower: &[f64],
    diagonal: &[f64],
    upper: &[f64],
    rhs: &mut [f64],
    factor: &mut CyclicFactor,
) -> Result<(), SingularPivot> {
    factor.factor(lower, diagonal, upper)?;
    factor.solve(rhs);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::tridiagonal::tests::dense_solve;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn matches_dense_solve_on_random_loops() {
        let mut rng = StdRng::seed_from_u64(11);
        for &n in &[3usize, 4, 5, 17, 100, 400] {
            // A loop's J W Jᵀ: edges around a perturbed polygon, random inverse masses.
            let points: Vec<[f64; 2]> = (0..n)
                .map(|i| {
                    let t = std::f64::consts::TAU * i as f64 / n as f64;
                    let r = rng.random_range(0.8..1.2);
                    [r * t.cos(), r * t.sin()]
                })
                .collect();
            let w: Vec<f64> = (0..n).map(|_| rng.random_range(0.1..10.0)).collect();
            let e: Vec<[f64; 2]> = (0..n)
                .map(|k| {
                    let (a, b) = (points[k], points[(k + 1) % n]);
                    [b[0] - a[0], b[1] - a[1]]
                })
                .collect();
            let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
            let diagonal: Vec<f64> = (0..n)
                .map(|k| 4.0 * dot(e[k], e[k]) * (w[k] + w[(k + 1) % n]))
                .collect();
            let upper: Vec<f64> = (0..n)
                .map(|k| -4.0 * w[(k + 1) % n] * dot(e[k], e[(k + 1) % n]))
                .collect();
            let lower: Vec<f64> = (0..n)
                .map(|k| -4.0 * w[k] * dot(e[k], e[(k + n - 1) % n]))
                .collect();
            let rhs: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();

            let mut dense = vec![vec![0.0; n]; n];
            for i in 0..n {
                dense[i][i] += diagonal[i];
                dense[i][(i + 1) % n] += upper[i];
                dense[i][(i + n - 1) % n] += lower[i];
            }
            let reference = dense_solve(&dense, &rhs);
            let mut x = rhs.clone();
            solve_cyclic_tridiagonal(
                &lower,
                &diagonal,
                &upper,
                &mut x,
                &mut CyclicFactor::default(),
            )
            .unwrap();
            let norm = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in x.iter().zip(&reference) {
                assert!((a - b).abs() <= 1e-9 * norm, "n {n}: {a} vs {b}");
            }
        }
    }
}
