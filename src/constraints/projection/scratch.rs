//! The projection's reusable buffers: sized once, reused every step, so a steady-state
//! solve allocates nothing.

use bevy::math::DVec2;

use crate::linalg::cyclic::CyclicFactor;
use crate::linalg::sparse::SparseFactor;
use crate::linalg::tridiagonal::TridiagonalFactor;

/// Reusable buffers for [`project_island`](super::project_island), sized by
/// [`IslandScratch::reserve`].
#[derive(Clone, Debug, Default)]
pub struct IslandScratch {
    pub(crate) correction: Vec<DVec2>,
    pub(crate) inverse_mass: Vec<f64>,
    pub(crate) locked: Vec<bool>,
    pub(crate) predicted_edge: Vec<DVec2>,
    pub(crate) edge: Vec<DVec2>,
    pub(crate) start_direction: Vec<DVec2>,
    pub(crate) constraint: Vec<f64>,
    pub(crate) lower: Vec<f64>,
    pub(crate) diagonal: Vec<f64>,
    pub(crate) upper: Vec<f64>,
    pub(crate) rhs: Vec<f64>,
    pub(crate) thomas: Vec<f64>,
    /// Each edge's impulse this projection (mass × length, tension positive): the sum of
    /// its Newton steps' `−2 λ |d|`.
    pub(crate) edge_impulse: Vec<f64>,
    pub(crate) factors: Factors,
    /// Re-stepping (`restep`): each particle's offset from its start of step and its
    /// velocity in the current substep, and each edge's impulse scaled to the step.
    pub(crate) substep_offset: Vec<DVec2>,
    pub(crate) substep_velocity: Vec<DVec2>,
    pub(crate) substep_impulse: Vec<f64>,
}

impl IslandScratch {
    /// Make room for islands of up to `edges` edges among `particles` particles
    /// (allocates only when growing).
    pub fn reserve(&mut self, edges: usize, particles: usize) {
        grow(&mut self.correction, particles, DVec2::ZERO);
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
        ] {
            grow(buffer, edges, 0.0);
        }
    }

    /// Make room for re-stepping an island of `edges` edges among `particles`.
    pub(crate) fn reserve_substeps(&mut self, edges: usize, particles: usize) {
        grow(&mut self.substep_offset, particles, DVec2::ZERO);
        grow(&mut self.substep_velocity, particles, DVec2::ZERO);
        grow(&mut self.substep_impulse, edges, 0.0);
    }

    /// The impulse each of the last projected island's `edges` edges carried (mass ×
    /// length; divided by dt² it is the edge's tension, positive when it pulls).
    pub fn edge_impulses(&self, edges: usize) -> &[f64] {
        &self.edge_impulse[..edges]
    }
}

fn grow<T: Clone>(buffer: &mut Vec<T>, n: usize, value: T) {
    if buffer.len() < n {
        buffer.resize(n, value);
    }
}

/// The factors an island's system may be kept in between solves.
#[derive(Clone, Debug, Default)]
pub(crate) struct Factors {
    pub(crate) open: TridiagonalFactor,
    pub(crate) cyclic: CyclicFactor,
    pub(crate) sparse: SparseFactor,
}
