//! Contact rows: the inequalities `Σ cᵢ n·vᵢ ≥ target` a projection must respect, and
//! their island-local form.

use bevy::math::DVec2;

use super::scratch::{IslandScratch, LocalRow, MAX_CONTACT_ROWS, NOT_IN_CHAIN};
use crate::model::PointEdgePair;

/// A contact that the projection must not make approach: `Σ cᵢ n·vᵢ ≥ target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactRow {
    /// The particles involved (packed indices).
    pub particles: [u32; 3],
    /// Their coefficients.
    pub coefficients: [f64; 3],
    /// The contact normal.
    pub normal: DVec2,
    /// The smallest allowed `Σ cᵢ n·vᵢ`.
    pub target: f64,
}

impl ContactRow {
    /// A point–edge pair along `normal`, with the current relative normal velocity as
    /// the target.
    pub fn point_edge(pair: PointEdgePair, normal: DVec2, velocity: &[DVec2]) -> ContactRow {
        let mut row = ContactRow {
            particles: pair.particles().map(|i| i as u32),
            coefficients: pair.coefficients(),
            normal,
            target: 0.0,
        };
        row.target = row.normal_velocity(velocity);
        row
    }

    /// `Σ cᵢ n·vᵢ` for these velocities.
    pub fn normal_velocity(&self, velocity: &[DVec2]) -> f64 {
        self.particles
            .iter()
            .zip(self.coefficients)
            .map(|(&p, c)| c * self.normal.dot(velocity[p as usize]))
            .sum()
    }
}

/// Edge residual (`|C| / L²`) below which the contacts may be settled and the edges
/// polished alone: the remaining corrections are then a millionth of an edge, too small
/// to disturb a contact.
pub(super) const POLISH_RESIDUAL: f64 = 1e-6;

/// Translate the contact rows touching the island into local rows (up to
/// [`MAX_CONTACT_ROWS`]), with their current slack.
pub(super) fn localize_contacts(
    contacts: &[ContactRow],
    particles: usize,
    particle: &impl Fn(usize) -> usize,
    velocity: &[DVec2],
    dt: f64,
    scratch: &mut IslandScratch,
) {
    scratch.rows.clear();
    if contacts.is_empty() {
        return;
    }
    for j in 0..particles {
        scratch.local_of[particle(j)] = j as u32;
    }
    for row in contacts {
        let mut local = LocalRow {
            normal: row.normal,
            slack: (row.normal_velocity(velocity) - row.target) * dt,
            ..Default::default()
        };
        for (&p, &c) in row.particles.iter().zip(&row.coefficients) {
            let j = scratch.local_of[p as usize];
            if j != NOT_IN_CHAIN && scratch.inverse_mass[j as usize] > 0.0 && c != 0.0 {
                local.entries[local.count] = (j, c);
                local.count += 1;
            }
        }
        if local.count > 0 && scratch.rows.len() < MAX_CONTACT_ROWS {
            scratch.rows.push(local);
        }
    }
    // Which rows meet at which particle, for the N W Nᵀ terms.
    scratch.row_particles.clear();
    for (c, row) in scratch.rows.iter().enumerate() {
        for &(j, coefficient) in &row.entries[..row.count] {
            scratch.row_particles.push((j, c as u32, coefficient));
        }
    }
    scratch
        .row_particles
        .sort_unstable_by_key(|&(j, c, _)| (j, c));
    for j in 0..particles {
        scratch.local_of[particle(j)] = NOT_IN_CHAIN;
    }
}

/// How far the most violated row falls short, given the corrections so far.
pub(super) fn contact_violation(rows: &[LocalRow], correction: &[DVec2]) -> f64 {
    rows.iter()
        .map(|row| -(row.slack + row_change(row, correction)))
        .fold(0.0, f64::max)
}

/// `Σ cᵢ n·Δᵢ` of a row for per-particle corrections Δ.
pub(super) fn row_change(row: &LocalRow, correction: &[DVec2]) -> f64 {
    row.entries[..row.count]
        .iter()
        .map(|&(j, c)| c * row.normal.dot(correction[j as usize]))
        .sum()
}
