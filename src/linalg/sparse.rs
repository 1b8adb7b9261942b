//! Sparse LDLᵀ for the constraint systems of trees and general graphs.
//!
//! The unknowns are edges, and `A_kl ≠ 0` when edges k and l share a free particle. The
//! symbolic phase ([`SparsePlan::new`], once per topology change) orders the unknowns by
//! minimum degree — on a tree that eliminates edges from the leaves in, with little or
//! no fill — and records the filled pattern and every update the numeric phase will do,
//! so that factoring ([`SparseFactor::factor`]) is a flat loop with no search and no
//! allocation.
//!
//! A constraint that depends on the others (a braced square in 2D: more edges than
//! its particles have degrees of freedom) leaves a pivot that is zero up to round-off.
//! Its column is dropped — its multiplier is zero — so a consistent set of redundant
//! constraints is still met, by the others.

use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap};

use super::pivot::{Pivot, SingularPivot, positive_definite};

/// The elimination order, filled pattern and update list of a symmetric sparse matrix.
///
/// Values are indexed as the factor stores them: the diagonal of unknown j (in
/// elimination order) at `j`, the off-diagonal slot s at `n + s`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SparsePlan {
    /// `order[j]`: the unknown, in the caller's numbering, eliminated j-th.
    pub order: Vec<u32>,
    column_start: Vec<u32>,
    row: Vec<u32>,
    update_start: Vec<u32>,
    updates: Vec<[u32; 3]>,
}

impl SparsePlan {
    /// Plan the factorization of an `n × n` matrix whose off-diagonal non-zeros are
    /// `pairs` (either order, repeats allowed), in the caller's numbering.
    pub fn new(n: usize, pairs: &[(u32, u32)]) -> SparsePlan {
        let mut adjacent: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); n];
        for &(a, b) in pairs.iter().filter(|(a, b)| a != b) {
            adjacent[a as usize].insert(b);
            adjacent[b as usize].insert(a);
        }
        // Minimum degree, with the fill made explicit as it happens.
        let mut heap: BinaryHeap<Reverse<(usize, u32)>> = (0..n)
            .map(|v| Reverse((adjacent[v].len(), v as u32)))
            .collect();
        let mut eliminated = vec![false; n];
        let mut order = Vec::with_capacity(n);
        let mut pattern: Vec<Vec<u32>> = Vec::with_capacity(n);
        while let Some(Reverse((degree, v))) = heap.pop() {
            let v_index = v as usize;
            if eliminated[v_index] || degree != adjacent[v_index].len() {
                continue; // a stale entry
            }
            eliminated[v_index] = true;
            let neighbours: Vec<u32> = std::mem::take(&mut adjacent[v_index]).into_iter().collect();
            for &a in &neighbours {
                let set = &mut adjacent[a as usize];
                set.remove(&v);
                set.extend(neighbours.iter().copied().filter(|&b| b != a));
                heap.push(Reverse((set.len(), a)));
            }
            order.push(v);
            pattern.push(neighbours);
        }
        let mut position = vec![0u32; n];
        for (j, &v) in order.iter().enumerate() {
            position[v as usize] = j as u32;
        }
        let mut column_start = vec![0u32];
        let mut row = Vec::new();
        for neighbours in &pattern {
            let mut rows: Vec<u32> = neighbours.iter().map(|&u| position[u as usize]).collect();
            rows.sort_unstable();
            row.extend(rows);
            column_start.push(row.len() as u32);
        }
        let mut plan = SparsePlan {
            order,
            column_start,
            row,
            update_start: vec![0],
            updates: Vec::new(),
        };
        for j in 0..n {
            let slots = plan.slots(j);
            for x in slots.clone() {
                for y in x..slots.end {
                    let (i, k) = (plan.row[x] as usize, plan.row[y] as usize);
                    let target = if i == k {
                        i
                    } else {
                        n + plan
                            .slot(k, i)
                            .expect("elimination closes the pattern under fill")
                    };
                    plan.updates
                        .push([target as u32, (n + x) as u32, (n + y) as u32]);
                }
            }
            plan.update_start.push(plan.updates.len() as u32);
        }
        plan
    }

    /// Unknowns.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Whether there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Values the factor stores: the diagonal and the off-diagonal slots.
    pub fn value_count(&self) -> usize {
        self.len() + self.row.len()
    }

    /// Off-diagonal entries of the factor beyond those of the matrix are the fill;
    /// this is their count plus the matrix's own.
    pub fn off_diagonal_count(&self) -> usize {
        self.row.len()
    }

    /// The off-diagonal slot of (`row`, `column`), both in elimination order with
    /// `row > column`, if that entry is in the filled pattern.
    pub fn slot(&self, row: usize, column: usize) -> Option<usize> {
        let slots = self.slots(column);
        self.row[slots.clone()]
            .binary_search(&(row as u32))
            .ok()
            .map(|i| slots.start + i)
    }

    /// The value index of entry (`i`, `j`) (elimination order, either triangle).
    pub fn value_index(&self, i: usize, j: usize) -> Option<usize> {
        match i.cmp(&j) {
            std::cmp::Ordering::Equal => Some(i),
            std::cmp::Ordering::Greater => self.slot(i, j).map(|s| self.len() + s),
            std::cmp::Ordering::Less => self.slot(j, i).map(|s| self.len() + s),
        }
    }

    fn slots(&self, column: usize) -> std::ops::Range<usize> {
        self.column_start[column] as usize..self.column_start[column + 1] as usize
    }
}

/// The numeric LDLᵀ factor of a matrix planned by a [`SparsePlan`].
#[derive(Clone, Debug, Default)]
pub struct SparseFactor {
    values: Vec<f64>,
    inverse_pivot: Vec<f64>,
    /// Columns dropped as dependent by the last factorization.
    pub dropped: u32,
}

impl SparseFactor {
    /// Zeroed storage for the matrix, to assemble into through
    /// [`SparsePlan::value_index`] before [`SparseFactor::factor`]. Allocates only when
    /// growing.
    pub fn values_mut(&mut self, plan: &SparsePlan) -> &mut [f64] {
        let count = plan.value_count();
        if self.values.len() < count {
            self.values.resize(count, 0.0);
        }
        if self.inverse_pivot.len() < plan.len() {
            self.inverse_pivot.resize(plan.len(), 0.0);
        }
        let values = &mut self.values[..count];
        values.fill(0.0);
        values
    }

    /// Factor the assembled matrix in place. A non-finite pivot is an error; a pivot
    /// that is zero relative to its diagonal drops its column (see the module doc).
    pub fn factor(&mut self, plan: &SparsePlan) -> Result<(), SingularPivot> {
        let n = plan.len();
        self.dropped = 0;
        // The inverse pivots first hold the original diagonal, the pivot's yardstick.
        self.inverse_pivot[..n].copy_from_slice(&self.values[..n]);
        for j in 0..n {
            let pivot = self.values[j];
            let slots = plan.slots(j);
            match positive_definite(pivot, self.inverse_pivot[j].abs()) {
                Pivot::Fail => return Err(SingularPivot { row: j }),
                Pivot::Drop => {
                    self.inverse_pivot[j] = 0.0;
                    self.values[n + slots.start..n + slots.end].fill(0.0);
                    self.dropped += 1;
                    continue;
                }
                Pivot::Keep => {}
            }
            self.inverse_pivot[j] = 1.0 / pivot;
            for value in &mut self.values[n + slots.start..n + slots.end] {
                *value /= pivot;
            }
            let updates = plan.update_start[j] as usize..plan.update_start[j + 1] as usize;
            for &[target, a, b] in &plan.updates[updates] {
                self.values[target as usize] -=
                    self.values[a as usize] * self.values[b as usize] * pivot;
            }
        }
        Ok(())
    }

    /// Solve `A x = rhs` in place (elimination order).
    pub fn solve(&self, plan: &SparsePlan, rhs: &mut [f64]) {
        self.solve_many(plan, rhs, 1);
    }

    /// Solve `A X = B` in place for `k` right-hand sides stored row by row:
    /// `columns[i * k + c]` is row i of column c (elimination order).
    pub fn solve_many(&self, plan: &SparsePlan, columns: &mut [f64], k: usize) {
        let n = plan.len();
        if k == 0 {
            return;
        }
        for j in 0..n {
            let (done, rest) = columns.split_at_mut((j + 1) * k);
            let source = &done[j * k..];
            for s in plan.slots(j) {
                let (i, l) = (plan.row[s] as usize, self.values[n + s]);
                let target = &mut rest[(i - j - 1) * k..(i - j) * k];
                for (x, y) in target.iter_mut().zip(source) {
                    *x -= l * y;
                }
            }
        }
        for j in 0..n {
            let inverse = self.inverse_pivot[j];
            for x in &mut columns[j * k..(j + 1) * k] {
                *x *= inverse;
            }
        }
        for j in (0..n).rev() {
            let (head, rest) = columns.split_at_mut((j + 1) * k);
            let target = &mut head[j * k..];
            for s in plan.slots(j) {
                let (i, l) = (plan.row[s] as usize, self.values[n + s]);
                let source = &rest[(i - j - 1) * k..(i - j) * k];
                for (x, y) in target.iter_mut().zip(source) {
                    *x -= l * y;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// Dense `A x` for a symmetric matrix given by its entries in the caller's order.
    fn solve_and_check(n: usize, pairs: &[(u32, u32)], rng: &mut StdRng) -> usize {
        let plan = SparsePlan::new(n, pairs);
        // A random SPD matrix on the pattern: B Bᵀ-like via diagonal dominance.
        let mut dense = vec![0.0; n * n];
        for &(a, b) in pairs {
            let v = rng.random_range(-1.0..1.0);
            dense[a as usize * n + b as usize] = v;
            dense[b as usize * n + a as usize] = v;
        }
        for i in 0..n {
            let off: f64 = (0..n)
                .filter(|&j| j != i)
                .map(|j| f64::abs(dense[i * n + j]))
                .sum();
            dense[i * n + i] = off + rng.random_range(0.1..2.0);
        }
        let mut factor = SparseFactor::default();
        let values = factor.values_mut(&plan);
        let position: Vec<usize> = {
            let mut p = vec![0; n];
            for (j, &v) in plan.order.iter().enumerate() {
                p[v as usize] = j;
            }
            p
        };
        for a in 0..n {
            for b in 0..=a {
                if dense[a * n + b] != 0.0 {
                    let index = plan
                        .value_index(position[a], position[b])
                        .expect("every entry of the matrix has a place");
                    values[index] = dense[a * n + b];
                }
            }
        }
        factor.factor(&plan).unwrap();
        assert_eq!(factor.dropped, 0);
        let x: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let b: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| dense[i * n + j] * x[j]).sum())
            .collect();
        // Two right-hand sides at once: b and 2b.
        let mut columns = vec![0.0; 2 * n];
        for (j, &v) in plan.order.iter().enumerate() {
            columns[2 * j] = b[v as usize];
            columns[2 * j + 1] = 2.0 * b[v as usize];
        }
        factor.solve_many(&plan, &mut columns, 2);
        for (j, &v) in plan.order.iter().enumerate() {
            let expected = x[v as usize];
            assert!((columns[2 * j] - expected).abs() < 1e-11, "{n} unknowns");
            assert!((columns[2 * j + 1] - 2.0 * expected).abs() < 1e-11);
        }
        plan.off_diagonal_count()
    }

    #[test]
    fn random_sparse_systems_match_the_dense_solution() {
        let mut rng = StdRng::seed_from_u64(11);
        for n in [1usize, 2, 5, 20, 100, 300] {
            let count = rng.random_range(0..3 * n);
            let pairs: Vec<(u32, u32)> = (0..count)
                .map(|_| (rng.random_range(0..n) as u32, rng.random_range(0..n) as u32))
                .collect();
            solve_and_check(n, &pairs, &mut rng);
        }
    }

    #[test]
    fn a_star_of_chains_factors_without_fill() {
        // The line graph of a tree (edges sharing a particle form cliques): three
        // chains of edges meeting at one particle.
        let mut rng = StdRng::seed_from_u64(5);
        let (arms, length) = (3u32, 10u32);
        let mut pairs = Vec::new();
        for arm in 0..arms {
            let base = arm * length;
            pairs.extend((0..length - 1).map(|k| (base + k, base + k + 1)));
            for other in arm + 1..arms {
                pairs.push((base, other * length)); // the three first edges meet
            }
        }
        let entries = solve_and_check((arms * length) as usize, &pairs, &mut rng);
        assert_eq!(entries, pairs.len(), "no fill");
    }

    #[test]
    fn a_dependent_column_is_dropped() {
        // Rank one: [[1, 1], [1, 1]].
        let plan = SparsePlan::new(2, &[(0, 1)]);
        let mut factor = SparseFactor::default();
        let values = factor.values_mut(&plan);
        values.fill(1.0);
        factor.factor(&plan).unwrap();
        assert_eq!(factor.dropped, 1);
        let mut rhs = [2.0, 2.0];
        factor.solve(&plan, &mut rhs);
        // A solution of the consistent system, not an overflow.
        assert!((rhs[0] + rhs[1] - 2.0).abs() < 1e-14, "{rhs:?}");
    }
}
