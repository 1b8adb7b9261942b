//! Linear complementarity problems: find `μ ≥ 0` with `S μ + q ≥ 0` and
//! `μ·(S μ + q) = 0`, for a small symmetric positive semidefinite `S`.

/// Solve the complementarity problem `S μ + q ≥ 0, μ ≥ 0, μ·(S μ + q) = 0` for a small
/// symmetric positive semidefinite `S` (row-major) by projected Gauss–Seidel, until no
/// sweep moves any row's residual by more than `tolerance`. The residual `S μ + q` is
/// kept up to date as μ changes, so rows that stay inactive cost nothing.
pub fn projected_gauss_seidel(
    schur: &[f64],
    offset: &[f64],
    tolerance: f64,
    mu: &mut [f64],
    residual: &mut [f64],
) {
    let n = offset.len();
    mu.fill(0.0);
    residual.copy_from_slice(offset);
    for _sweep in 0..200 {
        let mut change = 0.0f64;
        for c in 0..n {
            let diagonal = schur[c * n + c];
            if diagonal <= 0.0 {
                continue;
            }
            let updated = (mu[c] - residual[c] / diagonal).max(0.0);
            let delta = updated - mu[c];
            if delta == 0.0 {
                continue;
            }
            mu[c] = updated;
            // S is symmetric: column c is row c.
            for (r, s) in residual.iter_mut().zip(&schur[c * n..(c + 1) * n]) {
                *r += s * delta;
            }
            change = change.max(delta.abs() * diagonal);
        }
        if change <= tolerance {
            break;
        }
    }
}
