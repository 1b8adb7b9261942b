//! The pattern of a symmetric quasi-definite matrix numbered in elimination order, its
//! elimination tree and factor column counts: the analysis the supernodal factorization
//! (`supernodal`) plans from. The column-by-column factorization here is its reference
//! in tests.
//!
//! The contact Newton's systems couple particles (positive definite blocks: masses, contact
//! stiffness) with edge multipliers (a zero diagonal), `[H Jᵀ; J 0]`. Numbered so that
//! every edge comes after the particles it joins, each pivot is of one sign — a
//! particle's positive, an edge's negative — and the factorization needs no pivoting.
//! An edge whose pivot vanishes depends on edges eliminated before it (a braced
//! square); its unknown is dropped (its multiplier is zero) and the others are solved.
//!
//! The tree and the counts are Davis's LDL's symbolic phase; its up-looking numeric
//! phase (row k of L the sparse triangular solve over the tree's row subtree) is the
//! reference.

/// No parent in the elimination tree.
const ROOT: u32 = u32::MAX;

#[cfg(test)]
use super::pivot::{Pivot, SingularPivot, quasi_definite};

/// The pattern of a symmetric matrix's upper triangle, by column, and its elimination
/// tree and column counts.
#[derive(Clone, Debug, Default)]
pub struct LdlPattern {
    /// Column k's entries are `row[start[k]..start[k + 1]]`, each at most k (the
    /// diagonal included), in any order.
    pub start: Vec<u32>,
    /// The row of each entry, column by column.
    pub row: Vec<u32>,
    parent: Vec<u32>,
    /// Where column k of L starts.
    l_start: Vec<u32>,
}

/// The numeric factor `L D Lᵀ`, column by column, and the buffers that make it.
#[cfg(test)]
#[derive(Clone, Debug, Default)]
pub struct LdlFactor {
    l_row: Vec<u32>,
    l_value: Vec<f64>,
    l_count: Vec<u32>,
    /// The pivots; an infinite one marks a dropped (dependent) unknown.
    pub diagonal: Vec<f64>,
    y: Vec<f64>,
    pattern: Vec<u32>,
    flag: Vec<u32>,
    /// Unknowns dropped as dependent in the last factorization.
    pub dropped: u32,
}

impl LdlPattern {
    /// The analysed pattern whose column k holds rows `row[start[k]..start[k + 1]]`.
    pub fn new(start: Vec<u32>, row: Vec<u32>) -> LdlPattern {
        let mut p = LdlPattern {
            start,
            row,
            ..Default::default()
        };
        p.analyze(&mut Vec::new());
        p
    }

    /// Unknowns.
    pub fn len(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// Whether there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Values stored (the matrix's upper triangle).
    pub fn values(&self) -> usize {
        self.row.len()
    }

    /// Each unknown's parent in the elimination tree (`u32::MAX` for a root).
    pub fn parent(&self) -> &[u32] {
        &self.parent
    }

    /// Each column's non-zeros below the diagonal in the factor, into `count`.
    pub fn column_counts_into(&self, count: &mut Vec<u32>) {
        count.clear();
        count.extend(self.l_start.windows(2).map(|w| w[1] - w[0]));
    }

    /// The factorization's work: Σ over columns of (non-zeros below the diagonal)².
    pub fn work(&self) -> f64 {
        self.l_start
            .windows(2)
            .map(|w| ((w[1] - w[0]) as f64).powi(2))
            .sum()
    }

    /// Non-zeros of L below the diagonal.
    pub fn factor_size(&self) -> usize {
        self.l_start.last().copied().unwrap_or(0) as usize
    }

    /// The elimination tree and column counts of the pattern in `start` and `row`
    /// (every entry's row at most its column). O(non-zeros of L).
    pub fn analyze(&mut self, flag: &mut Vec<u32>) {
        let n = self.len();
        self.parent.clear();
        self.parent.resize(n, ROOT);
        self.l_start.clear();
        self.l_start.resize(n + 1, 0);
        flag.clear();
        flag.resize(n, 0);
        let counts = &mut self.l_start[1..];
        for k in 0..n {
            flag[k] = k as u32;
            for &i in &self.row[self.start[k] as usize..self.start[k + 1] as usize] {
                let mut i = i as usize;
                while i < k && flag[i] != k as u32 {
                    if self.parent[i] == ROOT {
                        self.parent[i] = k as u32;
                    }
                    counts[i] += 1;
                    flag[i] = k as u32;
                    i = self.parent[i] as usize;
                }
            }
        }
        for k in 0..n {
            self.l_start[k + 1] += self.l_start[k];
        }
    }
}

#[cfg(test)]
impl LdlFactor {
    /// Factor the matrix with pattern `p` and values `value` (aligned with `p.row`).
    /// `scale[k]` is unknown k's natural pivot size: a pivot below
    /// [`DEPENDENT_PIVOT`](super::pivot::DEPENDENT_PIVOT) of it is dropped when `negative[k]` (an edge), and is an
    /// error otherwise. Each unknown's pivot must have the sign `negative` gives it.
    pub fn factor(
        &mut self,
        p: &LdlPattern,
        value: &[f64],
        scale: &[f64],
        negative: &[bool],
    ) -> Result<(), SingularPivot> {
        let n = p.len();
        let size = p.factor_size();
        self.l_row.resize(size, 0);
        self.l_value.resize(size, 0.0);
        self.l_count.clear();
        self.l_count.resize(n, 0);
        self.diagonal.clear();
        self.diagonal.resize(n, 0.0);
        self.y.clear();
        self.y.resize(n, 0.0);
        self.pattern.resize(n, 0);
        self.flag.clear();
        self.flag.resize(n, u32::MAX);
        self.dropped = 0;
        for k in 0..n {
            // Scatter column k of the upper triangle (row k of the lower) and find the
            // pattern of row k of L: the row subtree, in topological order at the top.
            let mut top = n;
            self.flag[k] = k as u32;
            let range = p.start[k] as usize..p.start[k + 1] as usize;
            for (&i, &a) in p.row[range.clone()].iter().zip(&value[range]) {
                let mut i = i as usize;
                self.y[i] += a;
                let mut length = 0;
                while self.flag[i] != k as u32 {
                    self.pattern[length] = i as u32;
                    length += 1;
                    self.flag[i] = k as u32;
                    i = p.parent[i] as usize;
                }
                while length > 0 {
                    top -= 1;
                    length -= 1;
                    self.pattern[top] = self.pattern[length];
                }
            }
            let mut d = self.y[k];
            self.y[k] = 0.0;
            for t in top..n {
                let i = self.pattern[t] as usize;
                let yi = self.y[i];
                self.y[i] = 0.0;
                let first = p.l_start[i] as usize;
                let end = first + self.l_count[i] as usize;
                for (&r, &l) in self.l_row[first..end].iter().zip(&self.l_value[first..end]) {
                    self.y[r as usize] -= l * yi;
                }
                let l_ki = yi / self.diagonal[i];
                d -= l_ki * yi;
                self.l_row[end] = k as u32;
                self.l_value[end] = l_ki;
                self.l_count[i] += 1;
            }
            match quasi_definite(d, scale[k], negative[k]) {
                Pivot::Drop => {
                    // Dependent: its multiplier is zero, and later rows see no coupling.
                    d = f64::NEG_INFINITY;
                    self.dropped += 1;
                }
                Pivot::Fail => return Err(SingularPivot { row: k }),
                Pivot::Keep => {}
            }
            self.diagonal[k] = d;
        }
        Ok(())
    }

    /// Solve `L D Lᵀ x = b` in place.
    pub fn solve(&self, p: &LdlPattern, x: &mut [f64]) {
        let n = p.len();
        for j in 0..n {
            let xj = x[j];
            if xj != 0.0 {
                let first = p.l_start[j] as usize;
                let end = first + self.l_count[j] as usize;
                for (&r, &l) in self.l_row[first..end].iter().zip(&self.l_value[first..end]) {
                    x[r as usize] -= l * xj;
                }
            }
        }
        for (x, d) in x.iter_mut().zip(&self.diagonal) {
            *x /= *d;
        }
        for j in (0..n).rev() {
            let first = p.l_start[j] as usize;
            let end = first + self.l_count[j] as usize;
            let mut s = x[j];
            for (&r, &l) in self.l_row[first..end].iter().zip(&self.l_value[first..end]) {
                s -= l * x[r as usize];
            }
            x[j] = s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// A dense symmetric matrix's upper triangle as a pattern and values.
    fn upper(a: &[Vec<f64>]) -> (LdlPattern, Vec<f64>) {
        let n = a.len();
        let mut p = LdlPattern {
            start: vec![0],
            ..Default::default()
        };
        let mut value = Vec::new();
        for k in 0..n {
            for (i, row) in a.iter().enumerate().take(k + 1) {
                if row[k] != 0.0 || i == k {
                    p.row.push(i as u32);
                    value.push(row[k]);
                }
            }
            p.start.push(p.row.len() as u32);
        }
        p.analyze(&mut Vec::new());
        (p, value)
    }

    fn multiply(a: &[Vec<f64>], x: &[f64]) -> Vec<f64> {
        a.iter()
            .map(|row| row.iter().zip(x).map(|(a, x)| a * x).sum())
            .collect()
    }

    /// A random saddle-point matrix `[H Jᵀ; J 0]` of `particles` unknowns (H sparse
    /// SPD) and `constraints` rows each touching two particles, numbered with every
    /// constraint after both of its particles.
    fn saddle(
        rng: &mut StdRng,
        particles: usize,
        constraints: usize,
    ) -> (Vec<Vec<f64>>, Vec<bool>) {
        let n = particles + constraints;
        let mut a = vec![vec![0.0; n]; n];
        let mut order: Vec<(usize, bool)> = Vec::new();
        let mut ends = Vec::new();
        for c in 0..constraints {
            let i = rng.random_range(0..particles);
            let mut j = rng.random_range(0..particles);
            while j == i {
                j = rng.random_range(0..particles);
            }
            ends.push((c, i.max(j), i.min(j)));
        }
        for i in 0..particles {
            order.push((i, false));
            for &(c, last, _) in &ends {
                if last == i {
                    order.push((c, true));
                }
            }
        }
        let index: Vec<usize> = {
            let mut index = vec![0; n];
            for (k, &(u, edge)) in order.iter().enumerate() {
                index[if edge { particles + u } else { u }] = k;
            }
            index
        };
        for i in 0..particles {
            a[index[i]][index[i]] = rng.random_range(1.0..3.0);
        }
        for _ in 0..particles {
            let (i, j) = (
                rng.random_range(0..particles),
                rng.random_range(0..particles),
            );
            if i != j {
                let w = rng.random_range(0.0..0.5);
                a[index[i]][index[i]] += w;
                a[index[j]][index[j]] += w;
                a[index[i]][index[j]] -= w;
                a[index[j]][index[i]] -= w;
            }
        }
        for &(c, i, j) in &ends {
            let (u, v) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let (c, i, j) = (index[particles + c], index[i], index[j]);
            a[c][i] = u;
            a[i][c] = u;
            a[c][j] = v;
            a[j][c] = v;
        }
        let negative = order.iter().map(|&(_, edge)| edge).collect();
        (a, negative)
    }

    #[test]
    fn random_saddle_systems_are_solved_as_dense_ones() {
        let mut rng = StdRng::seed_from_u64(11);
        for trial in 0..60 {
            let particles = rng.random_range(2..40);
            let constraints = rng.random_range(0..particles.max(2) / 2 + 1);
            let (a, negative) = saddle(&mut rng, particles, constraints);
            let n = a.len();
            let (p, value) = upper(&a);
            let mut f = LdlFactor::default();
            f.factor(&p, &value, &vec![1.0; n], &negative)
                .unwrap_or_else(|e| panic!("trial {trial}: {e:?}"));
            let x: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mut b = multiply(&a, &x);
            f.solve(&p, &mut b);
            if f.dropped == 0 {
                let error = b
                    .iter()
                    .zip(&x)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(error < 1e-9, "trial {trial}: {error}");
            }
        }
    }

    #[test]
    fn a_dependent_constraint_is_dropped_and_the_rest_met() {
        // Two particles (one unknown each) and two identical constraints x0 − x1 = r.
        let a = vec![
            vec![1.0, 0.0, 1.0, 1.0],
            vec![0.0, 2.0, -1.0, -1.0],
            vec![1.0, -1.0, 0.0, 0.0],
            vec![1.0, -1.0, 0.0, 0.0],
        ];
        let (p, value) = upper(&a);
        let mut f = LdlFactor::default();
        f.factor(&p, &value, &[1.0; 4], &[false, false, true, true])
            .unwrap();
        assert_eq!(f.dropped, 1);
        // Right-hand side: no force, and both constraints ask for x0 − x1 = 0.3.
        let mut x = vec![0.0, 0.0, 0.3, 0.3];
        f.solve(&p, &mut x);
        assert!((x[0] - x[1] - 0.3).abs() < 1e-12, "{x:?}");
        assert_eq!(x[3], 0.0);
        // The forces balance: H x + Jᵀ λ = 0.
        assert!((x[0] + x[2]).abs() < 1e-12 && (2.0 * x[1] - x[2]).abs() < 1e-12);
    }

    #[test]
    fn a_pivot_of_the_wrong_sign_is_refused() {
        let a = vec![vec![-1.0, 0.0], vec![0.0, 1.0]];
        let (p, value) = upper(&a);
        let error = LdlFactor::default().factor(&p, &value, &[1.0; 2], &[false, false]);
        assert_eq!(error, Err(SingularPivot { row: 0 }));
    }
}
