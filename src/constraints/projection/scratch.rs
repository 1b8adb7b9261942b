//! The projection's reusable buffers: sized once, reused every step, so a steady-state
//! solve allocates nothing.

use bevy::math::DVec2;

use crate::constraints::complementarity::ActiveSetScratch;
use crate::constraints::cyclic::CyclicFactor;
use crate::constraints::sparse::SparseFactor;
use crate::constraints::tridiagonal::TridiagonalFactor;

/// Contact rows one projection takes at most; further ones are left to the collision
/// stage's verification.
pub const MAX_CONTACT_ROWS: usize = 256;

/// A contact row in island-local terms.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LocalRow {
    pub(super) entries: [(u32, f64); 3],
    pub(super) count: usize,
    pub(super) normal: DVec2,
    /// Current `Σ cᵢ n·vᵢ − target`, times dt (a distance per step).
    pub(super) slack: f64,
}

/// Reusable buffers for [`project_island`](super::project_island), sized by
/// [`IslandScratch::reserve`].
#[derive(Clone, Debug, Default)]
pub struct IslandScratch {
    pub(super) correction: Vec<DVec2>,
    pub(super) step_start: Vec<DVec2>,
    pub(super) inverse_mass: Vec<f64>,
    pub(super) locked: Vec<bool>,
    pub(super) predicted_edge: Vec<DVec2>,
    pub(super) edge: Vec<DVec2>,
    pub(super) start_direction: Vec<DVec2>,
    pub(super) constraint: Vec<f64>,
    pub(super) lower: Vec<f64>,
    pub(super) diagonal: Vec<f64>,
    pub(super) upper: Vec<f64>,
    pub(super) rhs: Vec<f64>,
    pub(super) thomas: Vec<f64>,
    /// Each edge's impulse this projection (mass × length, tension positive): the sum of
    /// its Newton steps' `−2 λ |d|`.
    pub(super) edge_impulse: Vec<f64>,
    /// The current Newton step's share of `edge_impulse`, before any trust shrink.
    pub(super) step_impulse: Vec<f64>,
    pub(super) factors: Factors,
    pub(super) local_of: Vec<u32>,
    pub(super) rows: Vec<LocalRow>,
    pub(super) columns: Vec<std::ops::Range<u32>>,
    pub(super) column_entries: Vec<(u32, f64)>,
    pub(super) solved_columns: Vec<f64>,
    pub(super) schur: Vec<f64>,
    /// Which columns of `schur` (and of `solved_columns`) the current step formed.
    pub(super) formed: Vec<bool>,
    pub(super) offset: Vec<f64>,
    pub(super) impulse: Vec<f64>,
    pub(super) contact_residual: Vec<f64>,
    pub(super) row_particles: Vec<(u32, u32, f64)>,
    pub(super) pivoting: ActiveSetScratch,
    /// Whether the contact problem is solved by pivoting (else iterated).
    pub(super) exact_contacts: bool,
}

impl IslandScratch {
    /// Make room for islands of up to `edges` edges among `particles` particles
    /// (allocates only when growing).
    pub fn reserve(&mut self, edges: usize, particles: usize) {
        grow(&mut self.correction, particles, DVec2::ZERO);
        grow(&mut self.step_start, particles, DVec2::ZERO);
        grow(&mut self.inverse_mass, particles, 0.0);
        grow(&mut self.locked, edges, false);
        grow(&mut self.predicted_edge, edges, DVec2::ZERO);
        grow(&mut self.edge, edges, DVec2::ZERO);
        grow(&mut self.start_direction, edges, DVec2::ZERO);
        for buffer in [
            &mut self.constraint,
            &mut self.lower,
            &mut self.diagonal,
            &mut self.upper,
            &mut self.rhs,
            &mut self.thomas,
            &mut self.edge_impulse,
            &mut self.step_impulse,
        ] {
            grow(buffer, edges, 0.0);
        }
    }

    /// The impulse each of the last projected island's `edges` edges carried (mass ×
    /// length; divided by dt² it is the edge's tension, positive when it pulls).
    pub fn edge_impulses(&self, edges: usize) -> &[f64] {
        &self.edge_impulse[..edges]
    }

    /// Make room for contact rows on islands of up to `edges` edges, at most `degree`
    /// of them at a particle, among `particles` packed particles.
    pub fn reserve_contacts(&mut self, edges: usize, degree: usize, particles: usize) {
        grow(&mut self.local_of, particles, NOT_IN_CHAIN);
        let rows = MAX_CONTACT_ROWS;
        self.rows.reserve(rows.saturating_sub(self.rows.len()));
        grow(&mut self.columns, rows, 0..0);
        grow(&mut self.solved_columns, rows * edges, 0.0);
        grow(&mut self.schur, rows * rows, 0.0);
        grow(&mut self.formed, rows, false);
        grow(&mut self.offset, rows, 0.0);
        grow(&mut self.impulse, rows, 0.0);
        grow(&mut self.contact_residual, rows, 0.0);
        self.pivoting.reserve(rows);
        self.row_particles
            .reserve((3 * rows).saturating_sub(self.row_particles.len()));
        // Up to `degree` edges at each of a row's three particles.
        self.column_entries
            .reserve((3 * degree * rows).saturating_sub(self.column_entries.len()));
    }
}

pub(super) const NOT_IN_CHAIN: u32 = u32::MAX;

fn grow<T: Clone>(buffer: &mut Vec<T>, n: usize, value: T) {
    if buffer.len() < n {
        buffer.resize(n, value);
    }
}

/// The factors an island's system may be kept in between solves.
#[derive(Clone, Debug, Default)]
pub(super) struct Factors {
    pub(super) open: TridiagonalFactor,
    pub(super) cyclic: CyclicFactor,
    pub(super) sparse: SparseFactor,
}
