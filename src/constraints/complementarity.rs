//! Linear complementarity problems: find `μ ≥ 0` with `S μ + q ≥ 0` and
//! `μ·(S μ + q) = 0`, for a small symmetric positive semidefinite `S`.
//!
//! [`active_set`] solves them to round-off by pivoting (the contact projection's
//! solver); [`projected_gauss_seidel`] iterates to a tolerance, the fallback when
//! pivoting stalls on a degenerate problem.

/// The matrix `S` of a complementarity problem, read a column at a time: the solvers
/// touch only the columns of rows that take an impulse, so a caller may form those
/// alone (most contact rows never do).
pub trait Schur {
    /// Column `c` of `S` (equal to its row: `S` is symmetric).
    fn column(&mut self, c: usize) -> &[f64];
    /// A stiffness of row `c` that ranks rows when pricing, `√S_cc` or a bound of the
    /// same scale; zero for a row that no impulse can move.
    fn scale(&self, c: usize) -> f64;
}

/// A fully formed symmetric `S`, row-major.
#[derive(Clone, Copy, Debug)]
pub struct DenseSchur<'a> {
    matrix: &'a [f64],
    n: usize,
}

impl<'a> DenseSchur<'a> {
    /// `matrix` is `n × n`, row-major.
    pub fn new(matrix: &'a [f64], n: usize) -> Self {
        assert_eq!(matrix.len(), n * n, "an n × n matrix");
        Self { matrix, n }
    }
}

impl Schur for DenseSchur<'_> {
    fn column(&mut self, c: usize) -> &[f64] {
        &self.matrix[c * self.n..(c + 1) * self.n]
    }

    fn scale(&self, c: usize) -> f64 {
        let diagonal = self.matrix[c * self.n + c];
        if diagonal > 0.0 { diagonal.sqrt() } else { 0.0 }
    }
}

/// Solve the complementarity problem `S μ + q ≥ 0, μ ≥ 0, μ·(S μ + q) = 0` for a small
/// symmetric positive semidefinite `S` by projected Gauss–Seidel, until no
/// sweep moves any row's residual by more than `tolerance` or `max_sweeps` are done.
/// The residual `S μ + q` is kept up to date as μ changes, so rows that stay inactive
/// cost nothing. Returns the sweeps taken.
pub fn projected_gauss_seidel(
    schur: &mut impl Schur,
    offset: &[f64],
    tolerance: f64,
    max_sweeps: u32,
    mu: &mut [f64],
    residual: &mut [f64],
) -> u32 {
    let n = offset.len();
    mu.fill(0.0);
    residual.copy_from_slice(offset);
    for sweep in 1..=max_sweeps {
        let mut change = 0.0f64;
        for c in 0..n {
            // A row without impulse and with a residual to spare stays so: its column
            // is not needed.
            if mu[c] == 0.0 && residual[c] >= 0.0 {
                continue;
            }
            let column = schur.column(c);
            let diagonal = column[c];
            if diagonal <= 0.0 {
                continue;
            }
            let updated = (mu[c] - residual[c] / diagonal).max(0.0);
            let delta = updated - mu[c];
            if delta == 0.0 {
                continue;
            }
            mu[c] = updated;
            for (r, s) in residual.iter_mut().zip(column) {
                *r += s * delta;
            }
            change = change.max(delta.abs() * diagonal);
        }
        if change <= tolerance {
            return sweep;
        }
    }
    max_sweeps
}

/// Reusable buffers of [`active_set`], for problems of up to `n` rows.
#[derive(Clone, Debug, Default)]
pub struct ActiveSetScratch {
    /// Rows of the active set, in the order of the factor.
    active: Vec<usize>,
    /// Where each row stands.
    status: Vec<RowStatus>,
    /// Lower Cholesky factor of `S` on the active set (row-major, `n × n`).
    factor: Vec<f64>,
    /// The unconstrained minimiser on the active set, then a work vector.
    target: Vec<f64>,
    work: Vec<f64>,
    /// `√S_cc` of each row (zero for a row with no stiffness): pricing reads it
    /// contiguously instead of striding down the diagonal at every pivot.
    stiffness: Vec<f64>,
}

impl ActiveSetScratch {
    /// Make room for problems of up to `n` rows (allocates only when growing).
    pub fn reserve(&mut self, n: usize) {
        if self.status.len() < n {
            self.status.resize(n, RowStatus::Inactive);
            self.factor.resize(n * n, 0.0);
            self.target.resize(n, 0.0);
            self.work.resize(n, 0.0);
            self.stiffness.resize(n, 0.0);
            self.active.reserve(n);
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum RowStatus {
    #[default]
    Inactive,
    Active,
    /// A combination of active rows: it cannot be met independently of them.
    Dependent,
}

/// A row whose stiffness left after the active rows' is below this fraction of its own
/// is treated as a combination of them (see [`active_set`]).
const DEPENDENT: f64 = 1e-9;

/// Why [`active_set`] gave up: the caller falls back to an iterative solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stalled;

/// Solve the complementarity problem `S μ + q ≥ 0, μ ≥ 0, μ·(S μ + q) = 0` for a small
/// symmetric positive semidefinite `S` exactly, by a primal active-set
/// method: the problem is the minimum of `½ μᵀSμ + qᵀμ` over `μ ≥ 0`, and Lawson and
/// Hanson's pivoting for non-negative least squares finds it in about as many pivots
/// as rows end active. A row joins while its residual is below `−tolerance`; the
/// minimiser on the active set is solved through a Cholesky factor grown a row at a
/// time, and a row whose impulse would turn negative leaves (then the factor is
/// rebuilt). A row that is a combination of the active ones (a semidefinite `S`:
/// contacts sharing their particles) joins in exchange for one of them, moving along
/// the direction that changes no residual; when no active impulse limits that move the
/// rows conflict — the problem has no solution, and pushing harder along the conflict
/// would grow the impulses without bound — and the row is left short.
///
/// Returns the pivots taken, or [`Stalled`] when the pivoting cycles on a degenerate
/// problem (after `4n + 8` pivots); `mu` and `residual` then hold the best point so far.
pub fn active_set(
    schur: &mut impl Schur,
    offset: &[f64],
    tolerance: f64,
    mu: &mut [f64],
    residual: &mut [f64],
    scratch: &mut ActiveSetScratch,
) -> Result<u32, Stalled> {
    let n = offset.len();
    scratch.reserve(n);
    let ActiveSetScratch {
        active,
        status,
        factor,
        target,
        work,
        stiffness,
    } = scratch;
    active.clear();
    status[..n].fill(RowStatus::Inactive);
    for (c, root) in stiffness[..n].iter_mut().enumerate() {
        *root = schur.scale(c);
    }
    mu.fill(0.0);
    residual.copy_from_slice(offset);
    let mut pivots = 0u32;
    let limit = 4 * n as u32 + 8;
    loop {
        // Price: the row whose residual most needs an impulse, per unit of its own
        // stiffness, so that scaling a row does not change which joins.
        let mut entering = None;
        let mut most = 0.0f64;
        for c in 0..n {
            if status[c] == RowStatus::Inactive && stiffness[c] > 0.0 && residual[c] < -tolerance {
                let scaled = residual[c] / stiffness[c];
                // The first of equal rows wins, as `min_by` would pick.
                if entering.is_none() || scaled.total_cmp(&most).is_lt() {
                    entering = Some(c);
                    most = scaled;
                }
            }
        }
        let Some(entering) = entering else {
            return Ok(pivots);
        };
        if !append_row(schur, n, entering, active, factor, work) {
            // The row is a combination `Σ αᵢ` of the active rows: moving along
            // `e_c − α` changes no residual and lowers the objective at the rate of the
            // row's negative residual, so go until an active impulse reaches zero and
            // exchange the two rows. With no such impulse the rows conflict.
            let k = active.len();
            let column = schur.column(entering);
            for (t, &r) in target[..k].iter_mut().zip(active.iter()) {
                *t = column[r];
            }
            cholesky_solve(factor, n, k, &mut target[..k]);
            let ratio = |i: usize| mu[active[i]] / target[i];
            let blocking = (0..k)
                .filter(|&i| target[i] > 0.0)
                .min_by(|&i, &j| ratio(i).total_cmp(&ratio(j)));
            let Some(b) = blocking else {
                status[entering] = RowStatus::Dependent;
                continue;
            };
            let step = ratio(b);
            for (i, &r) in active.iter().enumerate() {
                mu[r] = (mu[r] - step * target[i]).max(0.0);
            }
            let leaving = active.remove(b);
            mu[leaving] = 0.0;
            status[leaving] = RowStatus::Inactive;
            refactor(schur, n, active, b, factor, work);
            if !append_row(schur, n, entering, active, factor, work) {
                status[entering] = RowStatus::Dependent;
                continue;
            }
            mu[entering] = step;
            pivots += 1;
        }
        status[entering] = RowStatus::Active;
        loop {
            pivots += 1;
            if pivots > limit {
                return Err(Stalled);
            }
            let k = active.len();
            for (t, &c) in target[..k].iter_mut().zip(active.iter()) {
                *t = -offset[c];
            }
            cholesky_solve(&factor[..], n, k, &mut target[..k]);
            // Move from μ towards the target, as far as every active impulse stays
            // non-negative; a row that reaches zero leaves.
            let mut step = 1.0f64;
            for (i, &c) in active.iter().enumerate() {
                if target[i] <= 0.0 {
                    let ratio = mu[c] / (mu[c] - target[i]);
                    step = step.min(ratio);
                }
            }
            for (i, &c) in active.iter().enumerate() {
                mu[c] += step * (target[i] - mu[c]);
            }
            if step >= 1.0 {
                break;
            }
            let before = active.len();
            // Rows of the factor before the first that leaves stay as they are.
            let mut unchanged = active
                .iter()
                .position(|&c| mu[c] <= 0.0 || mu[c].is_nan())
                .unwrap_or(before);
            active.retain(|&c| {
                let keep = mu[c] > 0.0;
                if !keep {
                    mu[c] = 0.0;
                    status[c] = RowStatus::Inactive;
                }
                keep
            });
            // The row on which the step stopped leaves even if round-off kept it a
            // hair above zero.
            if active.len() == before {
                let blocking = active
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| target[i] <= 0.0)
                    .min_by(|&(i, &a), &(j, &b)| {
                        (mu[a] / (mu[a] - target[i])).total_cmp(&(mu[b] / (mu[b] - target[j])))
                    })
                    .map(|(i, _)| i);
                if let Some(i) = blocking {
                    let c = active.remove(i);
                    mu[c] = 0.0;
                    status[c] = RowStatus::Inactive;
                    unchanged = i;
                }
            }
            refactor(schur, n, active, unchanged, factor, work);
        }
        // w = S μ + q over the rows with an impulse.
        residual.copy_from_slice(offset);
        for &c in active.iter() {
            let column = schur.column(c);
            for (r, s) in residual.iter_mut().zip(column) {
                *r += s * mu[c];
            }
        }
    }
}

/// Grow the Cholesky factor of `S` on `active` by the row `c`, unless `c` is a
/// combination of the active rows (then `false`, and nothing changes).
fn append_row(
    schur: &mut impl Schur,
    n: usize,
    c: usize,
    active: &mut Vec<usize>,
    factor: &mut [f64],
    work: &mut [f64],
) -> bool {
    active.push(c);
    let independent = factor_row(schur.column(c), n, active, active.len() - 1, factor, work);
    if !independent {
        active.pop();
    }
    independent
}

/// Rebuild the factor on `active` from its row `from` on, after rows left there (a
/// subset of independent rows is independent; rows before `from` depend only on the
/// rows before them, which did not change).
fn refactor(
    schur: &mut impl Schur,
    n: usize,
    active: &[usize],
    from: usize,
    factor: &mut [f64],
    work: &mut [f64],
) {
    for i in from..active.len() {
        factor_row(schur.column(active[i]), n, active, i, factor, work);
    }
}

/// Row `i` of the Cholesky factor of `S` on `active`, from the rows before it and
/// the column of `S` at `active[i]`; `false` when the row is (nearly) a combination
/// of them.
fn factor_row(
    column: &[f64],
    n: usize,
    active: &[usize],
    i: usize,
    factor: &mut [f64],
    work: &mut [f64],
) -> bool {
    let c = active[i];
    // L[..i] l = S[active[..i], c], forward.
    for r in 0..i {
        let mut value = column[active[r]];
        for j in 0..r {
            value -= factor[r * n + j] * work[j];
        }
        work[r] = value / factor[r * n + r];
    }
    let diagonal = column[c];
    let remaining = diagonal - work[..i].iter().map(|l| l * l).sum::<f64>();
    factor[i * n..i * n + i].copy_from_slice(&work[..i]);
    factor[i * n + i] = remaining.max(DEPENDENT * diagonal).sqrt();
    remaining > DEPENDENT * diagonal
}

/// Solve `L Lᵀ x = b` in place on the first `k` rows of the factor.
fn cholesky_solve(factor: &[f64], n: usize, k: usize, b: &mut [f64]) {
    for i in 0..k {
        let mut value = b[i];
        for j in 0..i {
            value -= factor[i * n + j] * b[j];
        }
        b[i] = value / factor[i * n + i];
    }
    for i in (0..k).rev() {
        let mut value = b[i];
        for j in i + 1..k {
            value -= factor[j * n + i] * b[j];
        }
        b[i] = value / factor[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// `S = GᵀG` for a random `rank × n` matrix `G`: positive definite when
    /// `rank ≥ n`, semidefinite otherwise.
    fn random_problem(n: usize, rank: usize, rng: &mut StdRng) -> (Vec<f64>, Vec<f64>) {
        let g: Vec<f64> = (0..rank * n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut s = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                s[i * n + j] = (0..rank).map(|r| g[r * n + i] * g[r * n + j]).sum();
            }
        }
        let q = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        (s, q)
    }

    fn dense(s: &[f64]) -> DenseSchur<'_> {
        let n = (s.len() as f64).sqrt().round() as usize;
        DenseSchur::new(s, n)
    }

    /// A matrix that forms its columns when asked, recording which, and ranks rows by
    /// a scale other than `√S_cc` (as the contact projection's does).
    struct Recording<'a> {
        matrix: &'a [f64],
        n: usize,
        asked: Vec<bool>,
        scale: Vec<f64>,
    }

    impl Schur for Recording<'_> {
        fn column(&mut self, c: usize) -> &[f64] {
            self.asked[c] = true;
            &self.matrix[c * self.n..(c + 1) * self.n]
        }

        fn scale(&self, c: usize) -> f64 {
            self.scale[c]
        }
    }

    fn residual_of(s: &[f64], q: &[f64], mu: &[f64]) -> Vec<f64> {
        let n = q.len();
        (0..n)
            .map(|i| q[i] + (0..n).map(|j| s[i * n + j] * mu[j]).sum::<f64>())
            .collect()
    }

    /// Every subset tried as the active set: the one whose solve is feasible and
    /// complementary (unique for a positive definite `S`).
    fn brute_force(s: &[f64], q: &[f64]) -> Vec<f64> {
        let n = q.len();
        for subset in 0u32..(1 << n) {
            let active: Vec<usize> = (0..n).filter(|&i| subset & (1 << i) != 0).collect();
            let k = active.len();
            // Dense Gaussian elimination on S[active, active] z = −q[active].
            let mut a: Vec<f64> = (0..k * k)
                .map(|e| s[active[e / k] * n + active[e % k]])
                .collect();
            let mut z: Vec<f64> = active.iter().map(|&i| -q[i]).collect();
            for p in 0..k {
                for r in p + 1..k {
                    let f = a[r * k + p] / a[p * k + p];
                    for c in p..k {
                        a[r * k + c] -= f * a[p * k + c];
                    }
                    z[r] -= f * z[p];
                }
            }
            for p in (0..k).rev() {
                let tail: f64 = (p + 1..k).map(|c| a[p * k + c] * z[c]).sum();
                z[p] = (z[p] - tail) / a[p * k + p];
            }
            let mut mu = vec![0.0; n];
            for (i, &c) in active.iter().enumerate() {
                mu[c] = z[i];
            }
            let w = residual_of(s, q, &mu);
            if mu.iter().all(|&m| m >= -1e-12) && w.iter().all(|&x| x >= -1e-12) {
                return mu;
            }
        }
        panic!("a positive definite problem has a solution");
    }

    #[test]
    fn pivoting_finds_the_solution_every_active_set_is_tried_for() {
        let mut rng = StdRng::seed_from_u64(11);
        let mut scratch = ActiveSetScratch::default();
        for _ in 0..400 {
            let n = rng.random_range(1..=8);
            let (s, q) = random_problem(n, n + 2, &mut rng);
            let (mut mu, mut w) = (vec![0.0; n], vec![0.0; n]);
            active_set(&mut dense(&s), &q, 1e-14, &mut mu, &mut w, &mut scratch).unwrap();
            let expected = brute_force(&s, &q);
            for (a, b) in mu.iter().zip(&expected) {
                assert!(
                    (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
                    "{mu:?} {expected:?}"
                );
            }
            // The residual handed back is S μ + q.
            for (a, b) in w.iter().zip(residual_of(&s, &q, &mu)) {
                assert!((a - b).abs() <= 1e-12);
            }
        }
    }

    #[test]
    fn pivoting_reads_only_the_columns_of_rows_that_enter_whatever_the_scale() {
        let mut rng = StdRng::seed_from_u64(23);
        let mut scratch = ActiveSetScratch::default();
        let mut untouched = 0;
        for _ in 0..200 {
            let n = rng.random_range(1..=10);
            let (s, q) = random_problem(n, n + 2, &mut rng);
            let mut recording = Recording {
                matrix: &s,
                n,
                asked: vec![false; n],
                // An upper bound of √S_cc within a factor of three, like √(N W Nᵀ)_cc.
                scale: (0..n)
                    .map(|c| s[c * n + c].sqrt() * rng.random_range(1.0..3.0))
                    .collect(),
            };
            let (mut mu, mut w) = (vec![0.0; n], vec![0.0; n]);
            active_set(&mut recording, &q, 1e-14, &mut mu, &mut w, &mut scratch).unwrap();
            let expected = brute_force(&s, &q);
            for (a, b) in mu.iter().zip(&expected) {
                assert!(
                    (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
                    "{mu:?} {expected:?}"
                );
            }
            for c in 0..n {
                // A row that never needed an impulse is never read.
                if q[c] >= 0.0 && !recording.asked[c] {
                    untouched += 1;
                }
                if mu[c] > 0.0 {
                    assert!(recording.asked[c], "row {c} took an impulse unread");
                }
                if !recording.asked[c] {
                    assert_eq!(mu[c], 0.0);
                }
            }
        }
        // Random problems with q ≥ 0 rows: many columns are never formed.
        assert!(untouched > 200, "{untouched}");
    }

    #[test]
    fn gauss_seidel_reads_only_the_columns_of_rows_that_move() {
        let s = [2.0, 0.5, 0.0, 0.5, 2.0, 0.0, 0.0, 0.0, 2.0];
        let mut recording = Recording {
            matrix: &s,
            n: 3,
            asked: vec![false; 3],
            scale: vec![1.0; 3],
        };
        let (mut mu, mut w) = ([0.0; 3], [0.0; 3]);
        // Row 2 needs no impulse, and nothing pushes it: its column stays unformed.
        projected_gauss_seidel(
            &mut recording,
            &[-1.0, -1.0, 0.3],
            1e-14,
            100,
            &mut mu,
            &mut w,
        );
        assert_eq!(recording.asked, [true, true, false]);
        assert_eq!(mu[2], 0.0);
        // 2μ₀ + ½μ₁ = 1 = ½μ₀ + 2μ₁.
        assert!(
            (mu[0] - 0.4).abs() < 1e-12 && (mu[1] - 0.4).abs() < 1e-12,
            "{mu:?}"
        );
    }

    #[test]
    fn semidefinite_problems_end_feasible_and_complementary() {
        let mut rng = StdRng::seed_from_u64(5);
        let mut scratch = ActiveSetScratch::default();
        let tolerance = 1e-9;
        let mut stalled = 0;
        for _ in 0..200 {
            let n = rng.random_range(2..=64);
            // Rank below n: redundant rows, as when contacts share their particles.
            let rank = rng.random_range(1..n).max(n / 2);
            let (s, _) = random_problem(n, rank, &mut rng);
            // A solvable problem by construction: q = w* − S μ* for a complementary
            // pair μ*, w* ≥ 0.
            let star: Vec<f64> = (0..n)
                .map(|_| rng.random_range(-1.0f64..1.0).max(0.0))
                .collect();
            let pushed = residual_of(&s, &vec![0.0; n], &star);
            let q: Vec<f64> = (0..n)
                .map(|i| {
                    let slack = if star[i] > 0.0 {
                        0.0
                    } else {
                        rng.random_range(0.0..0.5)
                    };
                    slack - pushed[i]
                })
                .collect();
            let (mut mu, mut w) = (vec![0.0; n], vec![0.0; n]);
            if active_set(&mut dense(&s), &q, tolerance, &mut mu, &mut w, &mut scratch).is_err() {
                stalled += 1;
                continue;
            }
            let w = residual_of(&s, &q, &mu);
            let scale = 1.0 + mu.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for i in 0..n {
                assert!(mu[i] >= 0.0);
                assert!(w[i] >= -tolerance - 1e-8 * scale, "{i}: {}", w[i]);
                assert!(
                    (mu[i] * w[i]).abs() <= 1e-7 * scale * scale,
                    "{}",
                    mu[i] * w[i]
                );
            }
        }
        // Degenerate ties may stall the pivoting (the caller then iterates), rarely.
        assert!(stalled <= 4, "{stalled} of 200 stalled");
    }

    #[test]
    fn pivoting_and_gauss_seidel_agree_on_well_conditioned_problems() {
        let mut rng = StdRng::seed_from_u64(8);
        let mut scratch = ActiveSetScratch::default();
        for _ in 0..100 {
            let n = rng.random_range(1..=30);
            let (mut s, q) = random_problem(n, n, &mut rng);
            // Diagonally dominant, as contact rows on separate particles are.
            for i in 0..n {
                s[i * n + i] += n as f64;
            }
            let (mut a, mut wa) = (vec![0.0; n], vec![0.0; n]);
            let (mut b, mut wb) = (vec![0.0; n], vec![0.0; n]);
            active_set(&mut dense(&s), &q, 1e-13, &mut a, &mut wa, &mut scratch).unwrap();
            let sweeps = projected_gauss_seidel(&mut dense(&s), &q, 1e-13, 200, &mut b, &mut wb);
            assert!(
                sweeps < 200,
                "diagonally dominant: converges before the cap"
            );
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() <= 1e-9, "{x} {y}");
            }
        }
    }

    #[test]
    fn gauss_seidel_stops_at_its_sweep_cap_on_conflicting_rows() {
        // Two copies of one row asking for opposite signs of the same motion: no
        // solution, and the impulses grow every sweep.
        let s = [1.0, -1.0, -1.0, 1.0];
        let q = [-1.0, -1.0];
        let (mut mu, mut w) = ([0.0; 2], [0.0; 2]);
        assert_eq!(
            projected_gauss_seidel(&mut dense(&s), &q, 1e-12, 7, &mut mu, &mut w),
            7
        );
        assert!(mu.iter().all(|m| m.is_finite() && *m > 0.0), "{mu:?}");
    }

    #[test]
    fn a_problem_needing_no_impulse_takes_no_pivot() {
        let mut scratch = ActiveSetScratch::default();
        let (mut mu, mut w) = (vec![1.0; 2], vec![0.0; 2]);
        let pivots = active_set(
            &mut dense(&[2.0, 1.0, 1.0, 2.0]),
            &[0.5, 0.0],
            0.0,
            &mut mu,
            &mut w,
            &mut scratch,
        );
        assert_eq!(pivots, Ok(0));
        assert_eq!(mu, [0.0, 0.0]);
        assert_eq!(w, [0.5, 0.0]);
    }

    #[test]
    fn conflicting_rows_end_bounded_with_one_left_short() {
        // Two rows asking the same particle to move both ways: no μ meets both, and
        // the impulses stay those of meeting one.
        let mut scratch = ActiveSetScratch::default();
        let (mut mu, mut w) = (vec![0.0; 2], vec![0.0; 2]);
        let schur = [1.0, -1.0, -1.0, 1.0];
        active_set(
            &mut dense(&schur),
            &[-1.0, -0.5],
            1e-12,
            &mut mu,
            &mut w,
            &mut scratch,
        )
        .unwrap();
        assert_eq!(mu, [1.0, 0.0]);
        assert_eq!(w, [0.0, -1.5]);
    }
}
