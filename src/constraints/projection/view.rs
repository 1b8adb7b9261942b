//! What a projection reads and writes: the particle slices, and the island as a chain
//! or a graph.

use bevy::math::DVec2;

use crate::constraints::graph::GraphLayout;
use crate::constraints::island_edge::IslandEdge;
use crate::constraints::islands::{IslandKind, IslandSet};

/// The particle slices a projection reads and writes.
#[derive(Debug)]
pub struct Bodies<'a> {
    /// Positions at the start of the step.
    pub position: &'a [DVec2],
    /// Predictor velocities in, projected velocities out.
    pub velocity: &'a mut [DVec2],
    /// Inverse masses (0: pinned).
    pub inverse_mass: &'a [f64],
    /// Where a re-stepped island leaves what its particles' velocities change by once
    /// the step's positions are taken: its last substep's velocity less the step's
    /// chord (`None`: the chord is kept).
    pub end_change: Option<&'a mut [DVec2]>,
}

impl<'a> Bodies<'a> {
    /// The slices.
    pub fn new(position: &'a [DVec2], velocity: &'a mut [DVec2], inverse_mass: &'a [f64]) -> Self {
        Self {
            position,
            velocity,
            inverse_mass,
            end_change: None,
        }
    }

    /// The same slices, with `end_change` for re-stepped islands' end velocities.
    pub fn with_end_change(self, end_change: &'a mut [DVec2]) -> Self {
        Self {
            end_change: Some(end_change),
            ..self
        }
    }

    /// The same slices, reborrowed for one solve.
    pub fn reborrow(&mut self) -> Bodies<'_> {
        Bodies {
            position: self.position,
            velocity: &mut *self.velocity,
            inverse_mass: self.inverse_mass,
            end_change: self.end_change.as_deref_mut(),
        }
    }
}

/// A path or loop island: its edges in walking order (edge k + 1 starts where edge k
/// ends; when `closed`, the last ends where the first starts).
#[derive(Clone, Copy, Debug)]
pub struct Chain<'a> {
    /// The edges, in order.
    pub edges: &'a [IslandEdge],
    /// Whether the chain is a loop.
    pub closed: bool,
}

/// A tree or graph island: its edges in the layout's order, and the layout.
#[derive(Clone, Copy, Debug)]
pub struct Graph<'a> {
    /// The edges, in [`GraphLayout`] order.
    pub edges: &'a [IslandEdge],
    /// Local particles, incidence and the sparse plan.
    pub layout: &'a GraphLayout,
}

/// Any island the projection solves.
#[derive(Clone, Copy, Debug)]
pub enum IslandView<'a> {
    /// A path or a loop: a tridiagonal or cyclic tridiagonal system.
    Chain(Chain<'a>),
    /// A tree or graph: a sparse LDLᵀ.
    Graph(Graph<'a>),
}

impl<'a> IslandView<'a> {
    /// The view of island `island` of `set`.
    pub fn of(set: &'a IslandSet, island: usize) -> IslandView<'a> {
        let island = &set.islands[island];
        let edges = &set.edges[island.edges.clone()];
        match island.graph {
            Some(g) => IslandView::Graph(Graph {
                edges,
                layout: &set.graphs[g],
            }),
            None => IslandView::Chain(Chain {
                edges,
                closed: island.kind == IslandKind::Cycle,
            }),
        }
    }
}
