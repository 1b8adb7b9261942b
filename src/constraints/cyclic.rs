//! Cyclic tridiagonal systems (loops) in O(n): Sherman–Morrison on top of Thomas.
//!
//! A loop's matrix is tridiagonal plus the two corner entries that couple its last
//! edge to its first. Writing `A = T + u vᵀ`, with `T` tridiagonal, costs two Thomas
//! solves (`T y = b`, `T z = u`) and one correction.

use super::tridiagonal::{SingularPivot, solve_tridiagonal};

/// Buffers for [`solve_cyclic_tridiagonal`], each of at least `n` values.
#[derive(Clone, Debug, Default)]
pub struct CyclicScratch {
    diagonal: Vec<f64>,
    correction: Vec<f64>,
    thomas: Vec<f64>,
}

impl CyclicScratch {
    /// Make room for systems of `n` unknowns (allocates only when growing).
    pub fn reserve(&mut self, n: usize) {
        for buffer in [&mut self.diagonal, &mut self.correction, &mut self.thomas] {
            if buffer.len() < n {
                buffer.resize(n, 0.0);
            }
        }
    }
}

/// Solve `A x = rhs` for cyclic tridiagonal `A` (n ≥ 3), overwriting `rhs` with `x`.
///
/// Row `i` is `lower[i] x[i−1] + diagonal[i] x[i] + upper[i] x[i+1]` with indices
/// modulo `n`: `lower[0]` multiplies `x[n−1]` and `upper[n−1]` multiplies `x[0]`.
pub fn solve_cyclic_tridiagonal(
    lower: &[f64],
    diagonal: &[f64],
    upper: &[f64],
    rhs: &mut [f64],
    scratch: &mut CyclicScratch,
) -> Result<(), SingularPivot> {
    let n = rhs.len();
    assert!(n >= 3, "a cyclic system needs at least 3 unknowns");
    scratch.reserve(n);
    let CyclicScratch {
        diagonal: modified,
        correction: z,
        thomas,
    } = scratch;
    let (alpha, beta) = (upper[n - 1], lower[0]); // A[n−1][0], A[0][n−1]
    let gamma = -diagonal[0];
    modified[..n].copy_from_slice(&diagonal[..n]);
    modified[0] -= gamma;
    modified[n - 1] -= alpha * beta / gamma;

    solve_tridiagonal(lower, &modified[..n], upper, rhs, thomas)?;
    z[..n].fill(0.0);
    z[0] = gamma;
    z[n - 1] = alpha;
    solve_tridiagonal(lower, &modified[..n], upper, &mut z[..n], thomas)?;

    let numerator = rhs[0] + beta * rhs[n - 1] / gamma;
    let denominator = 1.0 + z[0] + beta * z[n - 1] / gamma;
    if !(denominator.is_finite() && denominator != 0.0) {
        return Err(SingularPivot { row: n - 1 });
    }
    let factor = numerator / denominator;
    for (x, zi) in rhs.iter_mut().zip(&z[..n]) {
        *x -= factor * zi;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::tridiagonal::tests::dense_solve;
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
                &mut CyclicScratch::default(),
            )
            .unwrap();
            let norm = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in x.iter().zip(&reference) {
                assert!((a - b).abs() <= 1e-9 * norm, "n {n}: {a} vs {b}");
            }
        }
    }
}
