//! Contacts inside a Newton step: the edge unknowns are eliminated through the
//! island's factor (one solve per contact column), leaving a small contact-space
//! complementarity problem `S μ + q ≥ 0, μ ≥ 0, μ·(S μ + q) = 0` with
//! `S = N W Nᵀ − Bᵀ A⁻¹ B`; its impulses μ then correct the edge multipliers.

use super::contact_rows::row_change;
use super::scratch::IslandScratch;
use super::walk::Walk;
use std::ops::Range;

use super::scratch::{Factors, LocalRow};
use crate::constraints::complementarity::{Schur, active_set, projected_gauss_seidel};

/// Sweeps of the iterative fallback per Newton step. It runs on the problems pivoting
/// could not settle, conflicting or nearly dependent rows, on which it does not
/// converge: in a dense pile at 1/600 it used 196 of 200 sweeps on average, a third of
/// the step's time. Its damped impulses are what the fallback is for; forty sweeps give
/// them, and the contact loop and the exact fail-safe finish what they leave.
const FALLBACK_SWEEPS: u32 = 40;

/// With `s.rhs` holding `A⁻¹(−C)` and the factor kept, solve for the contact impulses
/// (`s.impulse`) and subtract their effect from the edge multipliers in `s.rhs`.
pub(super) fn eliminate_contacts<W: Walk>(
    m: usize,
    walk: W,
    contact_tolerance: f64,
    s: &mut IslandScratch,
) {
    let rows = s.rows.len();
    // Columns b_c = J W N_cᵀ, sparse: the unlocked edges at the row's particles.
    s.column_entries.clear();
    for c in 0..rows {
        let row = s.rows[c];
        let start = s.column_entries.len();
        for &(j, coefficient) in &row.entries[..row.count] {
            let j = j as usize;
            let pushed = s.inverse_mass[j] * coefficient * row.normal;
            let (edge, locked, entries) = (&s.edge, &s.locked, &mut s.column_entries);
            walk.for_incident(j, m, |k, sign| {
                if locked[k] {
                    return;
                }
                let value = sign * 2.0 * edge[k].dot(pushed);
                match entries[start..].iter_mut().find(|(i, _)| *i as usize == k) {
                    Some(entry) => entry.1 += value,
                    None => entries.push((k as u32, value)),
                }
            });
        }
        s.columns[c] = start as u32..s.column_entries.len() as u32;
    }
    // The contact-space system S μ + q ≥ 0, μ ≥ 0, complementary:
    // S = N W Nᵀ − Bᵀ A⁻¹ B, q = slack + Bᵀ λ. q costs a few products a row; S is
    // formed a column at a time, for the rows that take an impulse.
    for c in 0..rows {
        let column = &s.column_entries[s.columns[c].start as usize..s.columns[c].end as usize];
        s.offset[c] = s.rows[c].slack
            + row_change(&s.rows[c], &s.correction)
            + column
                .iter()
                .map(|&(k, v)| v * s.rhs[k as usize])
                .sum::<f64>();
    }
    s.formed[..rows].fill(false);
    let mut schur = ContactSchur {
        m,
        walk,
        rows: &s.rows[..rows],
        columns: &s.columns[..rows],
        column_entries: &s.column_entries,
        row_particles: &s.row_particles,
        inverse_mass: &s.inverse_mass,
        factors: &s.factors,
        solved: &mut s.solved_columns[..rows * m],
        matrix: &mut s.schur[..rows * rows],
        formed: &mut s.formed[..rows],
    };
    // Pivoting solves the contact problem to round-off, so the edges' polish starts
    // from contacts met exactly; a degenerate problem on which it stalls is iterated,
    // and so is a projection that pivoting made ask for absurd corrections.
    let offset = &s.offset[..rows];
    let tolerance = 0.1 * contact_tolerance;
    let (mu, residual) = (&mut s.impulse[..rows], &mut s.contact_residual[..rows]);
    if !s.exact_contacts
        || active_set(&mut schur, offset, tolerance, mu, residual, &mut s.pivoting).is_err()
    {
        projected_gauss_seidel(&mut schur, offset, tolerance, FALLBACK_SWEEPS, mu, residual);
    }
    // λ = A⁻¹(−C) − Σ_c μ_c A⁻¹ b_c; a row with an impulse has its column formed.
    for c in 0..rows {
        let impulse = s.impulse[c];
        if impulse != 0.0 {
            debug_assert!(s.formed[c]);
            let solved = &s.solved_columns[c * m..(c + 1) * m];
            for (x, y) in s.rhs[..m].iter_mut().zip(solved) {
                *x -= impulse * y;
            }
        }
    }
}

/// The contact-space matrix of one Newton step, its columns formed on demand: column
/// `c` is one solve with the island's factor and a few products a row. In a dense pile
/// a projection carries a couple of hundred speculative rows of which a handful take
/// an impulse; forming all of `S` cost more than the rest of the projection.
struct ContactSchur<'a, W> {
    m: usize,
    walk: W,
    rows: &'a [LocalRow],
    columns: &'a [Range<u32>],
    column_entries: &'a [(u32, f64)],
    /// `(particle, row, coefficient)`, sorted by particle.
    row_particles: &'a [(u32, u32, f64)],
    inverse_mass: &'a [f64],
    factors: &'a Factors,
    /// `A⁻¹ b_c` of each formed column, `m` apiece.
    solved: &'a mut [f64],
    /// The formed columns, `n` apiece.
    matrix: &'a mut [f64],
    formed: &'a mut [bool],
}

impl<W: Walk> ContactSchur<'_, W> {
    fn entries(&self, c: usize) -> &[(u32, f64)] {
        &self.column_entries[self.columns[c].start as usize..self.columns[c].end as usize]
    }
}

impl<W: Walk> Schur for ContactSchur<'_, W> {
    fn column(&mut self, c: usize) -> &[f64] {
        let (n, m) = (self.rows.len(), self.m);
        if !self.formed[c] {
            let y = std::mem::take(&mut self.solved);
            let solved = &mut y[c * m..(c + 1) * m];
            solved.fill(0.0);
            for &(k, v) in self.entries(c) {
                solved[k as usize] = v;
            }
            self.walk.solve_many(m, self.factors, solved, 1);
            // −Bᵀ A⁻¹ b_c, every row's few entries against the solve.
            let matrix = std::mem::take(&mut self.matrix);
            let column = &mut matrix[c * n..(c + 1) * n];
            for (d, entry) in column.iter_mut().enumerate() {
                *entry = -self
                    .entries(d)
                    .iter()
                    .map(|&(k, v)| v * solved[k as usize])
                    .sum::<f64>();
            }
            // N W Nᵀ: the rows that share a particle with row c.
            let row = self.rows[c];
            for &(j, cc) in &row.entries[..row.count] {
                let first = self.row_particles.partition_point(|x| x.0 < j);
                let w = self.inverse_mass[j as usize];
                for &(_, d, cd) in self.row_particles[first..].iter().take_while(|x| x.0 == j) {
                    let normals = row.normal.dot(self.rows[d as usize].normal);
                    column[d as usize] += cc * cd * w * normals;
                }
            }
            self.solved = y;
            self.matrix = matrix;
            self.formed[c] = true;
        }
        &self.matrix[c * n..(c + 1) * n]
    }

    fn scale(&self, c: usize) -> f64 {
        // √(N W Nᵀ)_cc: the row's stiffness before the edges hold it, the same scale
        // as √S_cc (the edges only ever take stiffness away).
        let row = &self.rows[c];
        let free: f64 = row.entries[..row.count]
            .iter()
            .map(|&(j, cc)| cc * cc * self.inverse_mass[j as usize])
            .sum();
        free.max(0.0).sqrt()
    }
}
