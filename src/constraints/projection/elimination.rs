//! Contacts inside a Newton step: the edge unknowns are eliminated through the
//! island's factor (one solve per contact column), leaving a small contact-space
//! complementarity problem `S μ + q ≥ 0, μ ≥ 0, μ·(S μ + q) = 0` with
//! `S = N W Nᵀ − Bᵀ A⁻¹ B`; its impulses μ then correct the edge multipliers.

use super::contact_rows::row_change;
use super::scratch::IslandScratch;
use super::walk::Walk;
use crate::constraints::complementarity::{active_set, projected_gauss_seidel};

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
    // Columns b_c = J W N_cᵀ, then Y = A⁻¹ B, all columns at once (row-major).
    let solved = &mut s.solved_columns[..m * rows];
    solved.fill(0.0);
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
        for &(k, value) in &s.column_entries[start..] {
            solved[k as usize * rows + c] = value;
        }
        s.columns[c] = start as u32..s.column_entries.len() as u32;
    }
    walk.solve_many(m, &s.factors, solved, rows);
    // The contact-space system S μ + q ≥ 0, μ ≥ 0, complementary:
    // S = N W Nᵀ − Bᵀ A⁻¹ B, q = slack + Bᵀ λ.
    for c in 0..rows {
        let column = &s.column_entries[s.columns[c].start as usize..s.columns[c].end as usize];
        s.offset[c] = s.rows[c].slack
            + row_change(&s.rows[c], &s.correction)
            + column
                .iter()
                .map(|&(k, v)| v * s.rhs[k as usize])
                .sum::<f64>();
        // Bᵀ A⁻¹ B is symmetric: its upper triangle, mirrored below (half the work,
        // and S exactly symmetric, as pivoting's Cholesky factor assumes).
        let schur_row = &mut s.schur[c * rows + c..(c + 1) * rows];
        schur_row.fill(0.0);
        for &(k, v) in column {
            let solved_row = &solved[k as usize * rows + c..(k as usize + 1) * rows];
            for (entry, y) in schur_row.iter_mut().zip(solved_row) {
                *entry -= v * y;
            }
        }
    }
    for c in 1..rows {
        for d in 0..c {
            s.schur[c * rows + d] = s.schur[d * rows + c];
        }
    }
    // N W Nᵀ: only rows that share a particle meet.
    let w = &s.inverse_mass;
    for group in s.row_particles.chunk_by(|x, y| x.0 == y.0) {
        let j = group[0].0 as usize;
        for &(_, c, cc) in group {
            for &(_, d, cd) in group {
                let normals = s.rows[c as usize].normal.dot(s.rows[d as usize].normal);
                s.schur[c as usize * rows + d as usize] += cc * cd * w[j] * normals;
            }
        }
    }
    // Pivoting solves the contact problem to round-off, so the edges' polish starts
    // from contacts met exactly; a degenerate problem on which it stalls is iterated,
    // and so is a projection that pivoting made ask for absurd corrections.
    let (schur, offset) = (&s.schur[..rows * rows], &s.offset[..rows]);
    let tolerance = 0.1 * contact_tolerance;
    let (mu, residual) = (&mut s.impulse[..rows], &mut s.contact_residual[..rows]);
    if !s.exact_contacts
        || active_set(schur, offset, tolerance, mu, residual, &mut s.pivoting).is_err()
    {
        projected_gauss_seidel(schur, offset, tolerance, FALLBACK_SWEEPS, mu, residual);
    }
    // λ = A⁻¹(−C) − Y μ.
    for k in 0..m {
        let row = &s.solved_columns[k * rows..(k + 1) * rows];
        s.rhs[k] -= dot(row, &s.impulse[..rows]);
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
