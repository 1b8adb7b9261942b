//! The Thomas algorithm: a tridiagonal system in O(n), without pivoting.
//!
//! Safe without pivoting for the symmetric positive definite matrices of open strands
//! and for the nearly symmetric ones of the start-of-step direction. A
//! pivot that is not positive-finite relative to its row reports the system singular
//! instead of returning garbage.

use super::pivot::{SingularPivot, usable};

/// Solve `A x = rhs` for tridiagonal `A`, overwriting `rhs` with `x`.
///
/// Row `i` of `A` is `lower[i] x[i−1] + diagonal[i] x[i] + upper[i] x[i+1]`;
/// `lower[0]` and `upper[n−1]` are ignored. `scratch` holds at least `n` values.
/// Allocates nothing.
///
/// Thomas' cost is latency: each row's pivot needs the division by the one before.
/// Two things take the divisions off that chain. The elimination runs from both ends
/// at once and meets in the middle (a twisted factorization), two independent chains
/// of half the length. And each chain carries the leading minors `q_k = d_k q_{k−1} −
/// l_k u_{k−1} q_{k−2}` (pivot `q_k / q_{k−1}`) and the scaled right-hand side
/// `Y_k = q_{k−1} b_k − l_k Y_{k−1}` (eliminated value `Y_k / q_k`): multiplications
/// only, with one reciprocal per row that nothing later in the chain waits for. The
/// minors are rescaled by powers of two every two rows, exactly, so they neither
/// overflow nor underflow.
pub fn solve_tridiagonal(
    lower: &[f64],
    diagonal: &[f64],
    upper: &[f64],
    rhs: &mut [f64],
    scratch: &mut [f64],
) -> Result<(), SingularPivot> {
    let n = rhs.len();
    if n == 0 {
        return Ok(());
    }
    debug_assert!(lower.len() >= n && diagonal.len() >= n && upper.len() >= n);
    debug_assert!(scratch.len() >= n);
    let (lower, diagonal, upper, scratch) =
        (&lower[..n], &diagonal[..n], &upper[..n], &mut scratch[..n]);
    let last = n - 1;
    // Rows above `m` are eliminated downwards (x_i + scratch[i] x_{i+1} = rhs[i]), rows
    // below it upwards (x_i + scratch[i] x_{i−1} = rhs[i]); row `m` meets both. A bad
    // pivot only sets a flag: the loop stays free of branches, and a second pass over
    // the pivots alone names the row.
    let m = n / 2;
    let pairs = last - m; // rows below the middle; the rows above are `m` >= `pairs`
    let mut healthy = true;
    let mut chains = Chains::default();
    // Each lane's previous outward coupling: `linked` is the inward one times it.
    let mut previous_outward = [0.0; 2];
    let mut row = |k: usize, inward: [f64; 2], diagonal: [f64; 2], outward: [f64; 2], b| {
        let linked = [
            inward[0] * previous_outward[0],
            inward[1] * previous_outward[1],
        ];
        previous_outward = outward;
        let result = chains.eliminate(inward, diagonal, outward, linked, b);
        if k % RESCALE == RESCALE - 1 {
            chains.rescale();
        }
        result
    };
    // Lane 0: row k from above, coupled to k − 1 by lower[k] and to k + 1 by upper[k].
    // Lane 1: row j = last − k from below, coupled to j + 1 by upper[j] and to j − 1 by
    // lower[j]. In chain order: the first rows (no inward coupling), the rows between
    // (every coupling, no branch), then, when the rows above outnumber those below, the
    // last row above beside an idle row (1 on the diagonal). The end rows take one
    // general form, in two passes with the rows between after the first.
    for (stage, ends) in [0..m.min(1), pairs.max(1)..m].into_iter().enumerate() {
        for k in ends {
            let j = last - k;
            let paired = k < pairs;
            let inward = if k > 0 { lower[k] } else { 0.0 };
            let (diagonal, outward, b) = if paired {
                (
                    [diagonal[k], diagonal[j]],
                    [upper[k], lower[j]],
                    [rhs[k], rhs[j]],
                )
            } else {
                ([diagonal[k], 1.0], [upper[k], 0.0], [rhs[k], 0.0])
            };
            let (values, ratios, usable) = row(k, [inward, 0.0], diagonal, outward, b);
            healthy &= usable;
            (rhs[k], scratch[k]) = (values[0], ratios[0]);
            if paired {
                (rhs[j], scratch[j]) = (values[1], ratios[1]);
            }
        }
        if stage > 0 {
            break;
        }
        for k in 1..pairs {
            let j = last - k;
            let (values, ratios, usable) = row(
                k,
                [lower[k], upper[j]],
                [diagonal[k], diagonal[j]],
                [upper[k], lower[j]],
                [rhs[k], rhs[j]],
            );
            healthy &= usable;
            (rhs[k], scratch[k]) = (values[0], ratios[0]);
            (rhs[j], scratch[j]) = (values[1], ratios[1]);
        }
    }
    let from_above = if m > 0 { lower[m] } else { 0.0 };
    let from_below = if pairs > 0 { upper[m] } else { 0.0 };
    let (above, below) = (m.checked_sub(1), (pairs > 0).then_some(m + 1));
    let (above_ratio, above_value) = above.map_or((0.0, 0.0), |i| (scratch[i], rhs[i]));
    let (below_ratio, below_value) = below.map_or((0.0, 0.0), |i| (scratch[i], rhs[i]));
    let pivot = diagonal[m] - from_above * above_ratio - from_below * below_ratio;
    healthy &= usable(
        pivot,
        from_above.abs() + diagonal[m].abs() + from_below.abs(),
    );
    if !healthy {
        return Err(first_singular_row(lower, diagonal, upper));
    }
    let middle = (rhs[m] - from_above * above_value - from_below * below_value) / pivot;
    rhs[m] = middle;
    // Back-substitution outwards from the middle, both halves together, each in
    // registers (through memory, the store-to-load forwarding would sit on the chain)
    // and two rows at a time as two chains (see `Outward`).
    let (mut up, mut down) = (Outward::new(middle), Outward::new(middle));
    let mut k = 1;
    while k < pairs {
        let (i, j) = (m - k, m + k);
        let [x0, x1] = up.two([rhs[i], rhs[i - 1]], [scratch[i], scratch[i - 1]]);
        (rhs[i], rhs[i - 1]) = (x0, x1);
        let [x0, x1] = down.two([rhs[j], rhs[j + 1]], [scratch[j], scratch[j + 1]]);
        (rhs[j], rhs[j + 1]) = (x0, x1);
        k += 2;
    }
    for k in k..=m {
        let i = m - k;
        rhs[i] = up.one(rhs[i], scratch[i]);
        if k <= pairs {
            let j = m + k;
            rhs[j] = down.one(rhs[j], scratch[j]);
        }
    }
    Ok(())
}

/// One half's back-substitution, `x_i = y_i − r_i x_{i∓1}` away from the middle. Two
/// rows at a time it computes `x_{i+2} = (y_{i+2} − r_{i+2} y_{i+1}) + r_{i+2} r_{i+1}
/// x_i` beside `x_{i+1}`: each waits on a value two rows back, so the half runs as two
/// chains, and a row's latency halves.
struct Outward {
    /// The last two values, the nearer to the middle first.
    x: [f64; 2],
    /// The last row's eliminated value and outward ratio.
    y: f64,
    r: f64,
}

impl Outward {
    /// Starting at the middle row's value (its ratio taken as 0: nothing beyond it).
    fn new(middle: f64) -> Self {
        Self {
            x: [middle; 2],
            y: middle,
            r: 0.0,
        }
    }

    #[inline(always)]
    fn one(&mut self, y: f64, r: f64) -> f64 {
        let x = y - r * self.x[1];
        (self.x, self.y, self.r) = ([self.x[1], x], y, r);
        x
    }

    #[inline(always)]
    fn two(&mut self, y: [f64; 2], r: [f64; 2]) -> [f64; 2] {
        let first = (y[0] - r[0] * self.y) + (r[0] * self.r) * self.x[0];
        let second = (y[1] - r[1] * y[0]) + (r[1] * r[0]) * self.x[1];
        (self.x, self.y, self.r) = ([first, second], y[1], r[1]);
        [first, second]
    }
}

/// Rows between exact rescalings of the leading minors: two rows of pivots as small
/// as 1e-100 or as large as 1e100 stay inside the exponent range (strand systems'
/// pivots span a few decades around 1e-4); rescaling this often costs no measurable
/// time.
const RESCALE: usize = 2;

/// The two elimination chains' states, lane by lane (0 from above, 1 from below):
/// the last two leading minors and the last scaled right-hand side, each lane in its
/// own power-of-two scale. Both lanes go through the same operations, so the compiler
/// can pack them into vector instructions.
#[derive(Clone, Copy, Debug)]
struct Chains {
    previous: [f64; 2],
    before: [f64; 2],
    value: [f64; 2],
}

impl Default for Chains {
    fn default() -> Self {
        Self {
            previous: [1.0; 2],
            before: [0.0; 2],
            value: [0.0; 2],
        }
    }
}

impl Chains {
    /// Eliminate one row per lane (`inward` coupling, `diagonal`, `outward` coupling,
    /// `linked` = inward × the previous row's outward, right-hand side `b`): the
    /// eliminated values, the outward couplings over the pivots, and whether both
    /// pivots are usable.
    #[inline(always)]
    fn eliminate(
        &mut self,
        inward: [f64; 2],
        diagonal: [f64; 2],
        outward: [f64; 2],
        linked: [f64; 2],
        b: [f64; 2],
    ) -> ([f64; 2], [f64; 2], bool) {
        let (mut values, mut ratios, mut usable) = ([0.0; 2], [0.0; 2], [false; 2]);
        for l in 0..2 {
            let minor = diagonal[l] * self.previous[l] - linked[l] * self.before[l];
            let value = self.previous[l] * b[l] - inward[l] * self.value[l];
            let reciprocal = 1.0 / minor;
            let inverse_pivot = self.previous[l] * reciprocal;
            values[l] = value * reciprocal;
            ratios[l] = outward[l] * inverse_pivot;
            (self.before[l], self.previous[l], self.value[l]) = (self.previous[l], minor, value);
            // `usable(1 / inverse_pivot, row scale)` without the division.
            let scale = inward[l].abs() + diagonal[l].abs() + outward[l].abs();
            usable[l] = (inverse_pivot != 0.0) & (inverse_pivot.abs() * (1e-14 * scale) < 1.0);
        }
        (values, ratios, usable[0] & usable[1])
    }

    /// Multiply each lane by the power of two that brings its latest minor to [1, 2):
    /// exact, so every ratio is unchanged. The factor is 2^(1023 − e) for the minor's
    /// biased exponent e, built by one mask and one subtraction on its bits — this
    /// sits on the chain, so it is kept short. (A zero or subnormal minor gets 2^1023;
    /// an infinite or NaN one a non-finite factor, and the pivot check has already
    /// failed for it.)
    #[inline(always)]
    fn rescale(&mut self) {
        const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
        for l in 0..2 {
            let exponent = self.previous[l].to_bits() & EXPONENT;
            let factor = f64::from_bits(0x7fe0_0000_0000_0000_u64.wrapping_sub(exponent));
            self.previous[l] *= factor;
            self.before[l] *= factor;
            self.value[l] *= factor;
        }
    }
}

/// Whether a pivot is usable: finite and not negligible against its row.
/// The row at which [`solve_tridiagonal`]'s elimination broke down: its pivots again,
/// in its order, without the right-hand side.
fn first_singular_row(lower: &[f64], diagonal: &[f64], upper: &[f64]) -> SingularPivot {
    let n = diagonal.len();
    let (last, m) = (n - 1, n / 2);
    let (mut above, mut below) = (0.0, 0.0);
    for k in 0..m {
        let coupling = if k > 0 { lower[k] } else { 0.0 };
        let pivot = diagonal[k] - coupling * above;
        if !usable(pivot, coupling.abs() + diagonal[k].abs() + upper[k].abs()) {
            return SingularPivot { row: k };
        }
        above = upper[k] / pivot;
        let j = last - k;
        if j > m {
            let coupling = if k > 0 { upper[j] } else { 0.0 };
            let pivot = diagonal[j] - coupling * below;
            if !usable(pivot, coupling.abs() + diagonal[j].abs() + lower[j].abs()) {
                return SingularPivot { row: j };
            }
            below = lower[j] / pivot;
        }
    }
    SingularPivot { row: m }
}

/// A tridiagonal matrix with its Thomas elimination stored, to solve many right-hand
/// sides with multiplications only. Solving the right-hand sides together, row by row
/// ([`TridiagonalFactor::solve_many`]), replaces Thomas' latency-bound chain of
/// divisions with independent multiply-adds across the columns.
///
/// Eliminated from both ends to the middle row `n / 2`, like [`solve_tridiagonal`]:
/// a solve runs two chains of half the length side by side. Row `i` stores its inverse
/// pivot, its inward coupling over the pivot (towards the end it was eliminated from)
/// and its outward one (towards the middle); the middle row has two inward couplings.
#[derive(Clone, Debug, Default)]
pub struct TridiagonalFactor {
    inverse_pivot: Vec<f64>,
    inward: Vec<f64>,
    ratio: Vec<f64>,
    /// The middle row's coupling to the row below it, over its pivot.
    middle_below: f64,
}

impl TridiagonalFactor {
    /// Eliminate `A` (rows as in [`solve_tridiagonal`]). Allocates only when growing.
    pub fn factor(
        &mut self,
        lower: &[f64],
        diagonal: &[f64],
        upper: &[f64],
    ) -> Result<(), SingularPivot> {
        let n = diagonal.len();
        for buffer in [&mut self.inverse_pivot, &mut self.inward, &mut self.ratio] {
            buffer.clear();
            buffer.resize(n, 0.0);
        }
        self.middle_below = 0.0;
        if n == 0 {
            return Ok(());
        }
        let (last, m) = (n - 1, n / 2);
        // Row `row`, coupled to the row it is eliminated after by `inward` (that row's
        // ratio `previous`) and to the next one towards the middle by `outward`.
        let mut eliminate = |row: usize, inward: f64, outward: f64, previous: f64| {
            let pivot = diagonal[row] - inward * previous;
            check_pivot(
                pivot,
                inward.abs() + diagonal[row].abs() + outward.abs(),
                row,
            )?;
            let inverse = 1.0 / pivot;
            self.inverse_pivot[row] = inverse;
            self.inward[row] = inward * inverse;
            self.ratio[row] = outward * inverse;
            Ok::<f64, SingularPivot>(outward * inverse)
        };
        let mut previous = 0.0;
        for k in 0..m {
            let inward = if k > 0 { lower[k] } else { 0.0 };
            previous = eliminate(k, inward, upper[k], previous)?;
        }
        let above = previous;
        previous = 0.0;
        for j in (m + 1..n).rev() {
            let inward = if j < last { upper[j] } else { 0.0 };
            previous = eliminate(j, inward, lower[j], previous)?;
        }
        let below = previous;
        let from_above = if m > 0 { lower[m] } else { 0.0 };
        let from_below = if m < last { upper[m] } else { 0.0 };
        let pivot = diagonal[m] - from_above * above - from_below * below;
        check_pivot(
            pivot,
            from_above.abs() + diagonal[m].abs() + from_below.abs(),
            m,
        )?;
        let inverse = 1.0 / pivot;
        self.inverse_pivot[m] = inverse;
        self.inward[m] = from_above * inverse;
        self.middle_below = from_below * inverse;
        Ok(())
    }

    /// Unknowns of the factored system.
    pub fn len(&self) -> usize {
        self.inverse_pivot.len()
    }

    /// Whether the factored system is empty.
    pub fn is_empty(&self) -> bool {
        self.inverse_pivot.is_empty()
    }

    /// Solve `A x = rhs` in place.
    pub fn solve(&self, rhs: &mut [f64]) {
        self.solve_many(rhs, 1);
    }

    /// Solve `A X = B` in place for `k` right-hand sides stored row by row:
    /// `columns[i * k + c]` is row i of column c.
    pub fn solve_many(&self, columns: &mut [f64], k: usize) {
        match k {
            0 => {}
            1 => self.solve_rows::<1>(columns, 1, 0),
            2 => self.solve_rows::<2>(columns, 2, 0),
            _ => (0..k).for_each(|c| self.solve_rows::<1>(columns, k, c)),
        }
    }

    /// `K` columns from column `offset` of right-hand sides stored row by row, `stride`
    /// values a row, both halves' chains together; the row just solved stays in
    /// registers for the next (read back from memory, the store-to-load forwarding
    /// would sit on the chain).
    #[inline(always)]
    fn solve_rows<const K: usize>(&self, columns: &mut [f64], stride: usize, offset: usize) {
        let n = self.len();
        if n == 0 {
            return;
        }
        let (last, m) = (n - 1, n / 2);
        let at = |i: usize, c: usize| i * stride + offset + c;
        let (mut above, mut below) = ([0.0; K], [0.0; K]);
        for k in 0..m {
            let (inverse, inward) = (self.inverse_pivot[k], self.inward[k]);
            for c in 0..K {
                above[c] = columns[at(k, c)] * inverse - inward * above[c];
                columns[at(k, c)] = above[c];
            }
            let j = last - k;
            if j > m {
                let (inverse, inward) = (self.inverse_pivot[j], self.inward[j]);
                for c in 0..K {
                    below[c] = columns[at(j, c)] * inverse - inward * below[c];
                    columns[at(j, c)] = below[c];
                }
            }
        }
        let (inverse, from_above) = (self.inverse_pivot[m], self.inward[m]);
        for c in 0..K {
            let value =
                columns[at(m, c)] * inverse - from_above * above[c] - self.middle_below * below[c];
            columns[at(m, c)] = value;
            (above[c], below[c]) = (value, value);
        }
        for k in 1..=m {
            let i = m - k;
            let ratio = self.ratio[i];
            for c in 0..K {
                above[c] = columns[at(i, c)] - ratio * above[c];
                columns[at(i, c)] = above[c];
            }
            let j = m + k;
            if j < n {
                let ratio = self.ratio[j];
                for c in 0..K {
                    below[c] = columns[at(j, c)] - ratio * below[c];
                    columns[at(j, c)] = below[c];
                }
            }
        }
    }
}

fn check_pivot(pivot: f64, scale: f64, row: usize) -> Result<(), SingularPivot> {
    if usable(pivot, scale) {
        Ok(())
    } else {
        Err(SingularPivot { row })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// Gaussian elimination with partial pivoting on a dense copy: the reference.
    pub(crate) fn dense_solve(matrix: &[Vec<f64>], rhs: &[f64]) -> Vec<f64> {
        let n = rhs.len();
        let mut a: Vec<Vec<f64>> = matrix.to_vec();
        let mut b = rhs.to_vec();
        for col in 0..n {
            let p = (col..n)
                .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
                .unwrap();
            a.swap(col, p);
            b.swap(col, p);
            let pivot_row = a[col].clone();
            for row in col + 1..n {
                let f = a[row][col] / pivot_row[col];
                for (value, pivot) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                    *value -= f * pivot;
                }
                b[row] -= f * b[col];
            }
        }
        let mut x = vec![0.0; n];
        for row in (0..n).rev() {
            let s: f64 = (row + 1..n).map(|k| a[row][k] * x[k]).sum();
            x[row] = (b[row] - s) / a[row][row];
        }
        x
    }

    /// A random SPD tridiagonal matrix shaped like J W Jᵀ of a strand: diagonal
    /// 4|e_k|²(w_a + w_b), off-diagonal −4 w_s e_k·e_{k+1}, with edge lengths and
    /// inverse masses spread over `decades` orders of magnitude.
    fn strand_like(n: usize, decades: f64, rng: &mut StdRng) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let scale = |rng: &mut StdRng| 10f64.powf(rng.random_range(-decades..=decades) / 2.0);
        let edges: Vec<[f64; 2]> = (0..n)
            .map(|_| {
                let angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                let length = scale(rng);
                [length * angle.cos(), length * angle.sin()]
            })
            .collect();
        let w: Vec<f64> = (0..=n).map(|_| scale(rng)).collect();
        let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
        let diagonal: Vec<f64> = (0..n)
            .map(|k| 4.0 * dot(edges[k], edges[k]) * (w[k] + w[k + 1]))
            .collect();
        let mut upper = vec![0.0; n];
        let mut lower = vec![0.0; n];
        for k in 0..n.saturating_sub(1) {
            upper[k] = -4.0 * w[k + 1] * dot(edges[k], edges[k + 1]);
            lower[k + 1] = upper[k];
        }
        (lower, diagonal, upper)
    }

    fn dense(lower: &[f64], diagonal: &[f64], upper: &[f64]) -> Vec<Vec<f64>> {
        let n = diagonal.len();
        let mut m = vec![vec![0.0; n]; n];
        for i in 0..n {
            m[i][i] = diagonal[i];
            if i > 0 {
                m[i][i - 1] = lower[i];
            }
            if i + 1 < n {
                m[i][i + 1] = upper[i];
            }
        }
        m
    }

    /// Relative residual ‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞): backward error.
    fn backward_error(matrix: &[Vec<f64>], x: &[f64], b: &[f64]) -> f64 {
        let n = b.len();
        let norm_a = matrix
            .iter()
            .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let norm_x = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let norm_b = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let residual = (0..n)
            .map(|i| ((0..n).map(|k| matrix[i][k] * x[k]).sum::<f64>() - b[i]).abs())
            .fold(0.0, f64::max);
        residual / (norm_a * norm_x + norm_b)
    }

    #[test]
    fn matches_dense_solve_on_random_spd_systems() {
        let mut rng = StdRng::seed_from_u64(7);
        for &n in &[1usize, 2, 3, 5, 10, 31, 100, 257, 1000] {
            for decades in [0.0, 3.0, 8.0] {
                let (lower, diagonal, upper) = strand_like(n, decades, &mut rng);
                let rhs: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
                let mut x = rhs.clone();
                let mut scratch = vec![0.0; n];
                solve_tridiagonal(&lower, &diagonal, &upper, &mut x, &mut scratch).unwrap();
                let matrix = dense(&lower, &diagonal, &upper);
                // Thomas is backward stable on these: tiny residual at any scaling.
                let error = backward_error(&matrix, &x, &rhs);
                assert!(
                    error < 1e-14,
                    "n {n}, decades {decades}: backward error {error}"
                );
                if n <= 300 {
                    let reference = dense_solve(&matrix, &rhs);
                    let norm = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    let diff = x
                        .iter()
                        .zip(&reference)
                        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                    // Agreement bounded by the conditioning, which badly scaled systems
                    // inflate; the backward error above is the scale-free check.
                    let allowed = if decades == 0.0 { 1e-10 } else { 1e-6 };
                    assert!(
                        diff <= allowed * norm,
                        "n {n}, decades {decades}: {diff} vs {norm}"
                    );
                }
            }
        }
    }

    #[test]
    fn long_systems_of_tiny_or_huge_pivots_neither_overflow_nor_underflow() {
        // Leading minors of 5000 rows with pivots near 1e±100 leave the exponent range
        // within four rows: the chains' rescaling must keep them in it.
        let mut rng = StdRng::seed_from_u64(11);
        for magnitude in [1e-100, 1e100] {
            let n = 5000;
            let (lower, diagonal, upper) = strand_like(n, 0.0, &mut rng);
            let scaled = |v: &[f64]| v.iter().map(|x| x * magnitude).collect::<Vec<_>>();
            let (lower, diagonal, upper) = (scaled(&lower), scaled(&diagonal), scaled(&upper));
            let rhs: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mut x = rhs.clone();
            solve_tridiagonal(&lower, &diagonal, &upper, &mut x, &mut vec![0.0; n]).unwrap();
            // The residual row by row, relative to the row's terms.
            for i in 0..n {
                let mut terms = [diagonal[i] * x[i], 0.0, 0.0];
                if i > 0 {
                    terms[1] = lower[i] * x[i - 1];
                }
                if i + 1 < n {
                    terms[2] = upper[i] * x[i + 1];
                }
                let size: f64 = terms.iter().map(|t| t.abs()).sum::<f64>() + rhs[i].abs();
                let residual = (terms.iter().sum::<f64>() - rhs[i]).abs();
                assert!(
                    x[i].is_finite() && residual <= 1e-12 * size,
                    "magnitude {magnitude:e}, row {i}: residual {residual:e} of {size:e}"
                );
            }
        }
    }

    #[test]
    fn solves_an_unsymmetric_system() {
        let lower = [0.0, -1.0, 0.5, 2.0];
        let diagonal = [4.0, 5.0, 6.0, 7.0];
        let upper = [1.0, -2.0, 1.5, 0.0];
        let rhs = [1.0, 2.0, 3.0, 4.0];
        let mut x = rhs;
        solve_tridiagonal(&lower, &diagonal, &upper, &mut x, &mut [0.0; 4]).unwrap();
        let reference = dense_solve(&dense(&lower, &diagonal, &upper), &rhs);
        for (a, b) in x.iter().zip(reference) {
            assert!((a - b).abs() < 1e-14);
        }
    }

    #[test]
    fn a_factor_solves_many_right_hand_sides_like_one_at_a_time() {
        let mut rng = StdRng::seed_from_u64(13);
        let n = 37;
        let (lower, diagonal, upper) = strand_like(n, 2.0, &mut rng);
        let mut factor = TridiagonalFactor::default();
        factor.factor(&lower, &diagonal, &upper).unwrap();
        // One and two columns take the register-carried path, more the general one.
        for k in [1, 2, 5] {
            let columns: Vec<Vec<f64>> = (0..k)
                .map(|_| (0..n).map(|_| rng.random_range(-1.0..1.0)).collect())
                .collect();
            let mut together = vec![0.0; n * k];
            for (c, column) in columns.iter().enumerate() {
                for i in 0..n {
                    together[i * k + c] = column[i];
                }
            }
            factor.solve_many(&mut together, k);
            for (c, column) in columns.iter().enumerate() {
                let mut alone = column.clone();
                solve_tridiagonal(&lower, &diagonal, &upper, &mut alone, &mut vec![0.0; n])
                    .unwrap();
                for i in 0..n {
                    let tolerance = 1e-12 * alone[i].abs().max(1e-3);
                    assert!((together[i * k + c] - alone[i]).abs() <= tolerance, "k {k}");
                }
            }
        }
    }

    #[test]
    fn reports_a_singular_system() {
        // An edge of zero length has a zero row.
        let lower = [0.0, 0.0, 0.0];
        let diagonal = [1.0, 0.0, 1.0];
        let upper = [0.0, 0.0, 0.0];
        let mut x = [1.0, 1.0, 1.0];
        assert_eq!(
            solve_tridiagonal(&lower, &diagonal, &upper, &mut x, &mut [0.0; 3]),
            Err(SingularPivot { row: 1 })
        );
        // Either half's chain reports its own row.
        for zero in 0..5 {
            let mut diagonal = [2.0; 5];
            diagonal[zero] = 0.0;
            let mut x = [1.0; 5];
            assert_eq!(
                solve_tridiagonal(&[0.0; 5], &diagonal, &[0.0; 5], &mut x, &mut [0.0; 5]),
                Err(SingularPivot { row: zero })
            );
        }
    }
}
