//! How the projection walks an island's particles and edges and solves its system: a
//! generic parameter, so that the loops of each kind of island compile without a
//! branch per edge.

use super::assembly::{chain_solve, graph_solve};
use super::scratch::{Factors, IslandScratch};
use super::settings::ConstraintDirection;
use crate::constraints::graph::GraphLayout;
use crate::constraints::island_edge::IslandEdge;
use crate::linalg::SingularPivot;

/// An island's particles, edges and system.
pub(crate) trait Walk: Copy {
    /// Particles of the island of `edges`.
    fn particles(self, edges: &[IslandEdge]) -> usize;
    /// Packed index of local particle `j`.
    fn particle(self, edges: &[IslandEdge], j: usize) -> usize;
    /// Local ends of edge `k`.
    fn ends(self, k: usize, particles: usize) -> (usize, usize);
    /// The island edges at local particle `j`, with −1 where `j` starts the edge and +1
    /// where it ends it.
    fn for_incident(self, j: usize, m: usize, visit: impl FnMut(usize, f64));
    /// Whether the system must be the symmetric (end-of-step) one.
    fn symmetric_only(self) -> bool;
    /// Assemble and factor the system at the current iterate, and solve it for
    /// `s.rhs`; keep the factor for [`Walk::solve_many`] when `keep_factor`.
    fn solve(
        self,
        m: usize,
        direction: ConstraintDirection,
        keep_factor: bool,
        s: &mut IslandScratch,
    ) -> Result<(), SingularPivot>;
    /// Solve again with the kept factor `factors`, for `k` right-hand sides row by row.
    fn solve_many(self, m: usize, factors: &Factors, columns: &mut [f64], k: usize);
}

/// `$body` with `$edges` bound to an island's edges and `$walk` to its walk (a
/// [`ChainWalk`] or a [`GraphWalk`]): the one dispatch on an island's kind, each arm
/// compiled for its walk so the loops have no branch per edge.
macro_rules! with_walk {
    ($view:expr, |$edges:pat, $walk:ident| $body:expr) => {
        match $view {
            $crate::constraints::projection::IslandView::Chain(chain) => {
                let $edges = chain.edges;
                let $walk = $crate::constraints::projection::walk::ChainWalk {
                    closed: chain.closed,
                };
                $body
            }
            $crate::constraints::projection::IslandView::Graph(graph) => {
                let $edges = graph.edges;
                let $walk = $crate::constraints::projection::walk::GraphWalk {
                    layout: graph.layout,
                };
                $body
            }
        }
    };
}
pub(crate) use with_walk;

/// A path or a loop.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ChainWalk {
    pub(crate) closed: bool,
}

impl Walk for ChainWalk {
    fn particles(self, edges: &[IslandEdge]) -> usize {
        edges.len() + usize::from(!self.closed)
    }

    #[inline]
    fn particle(self, edges: &[IslandEdge], j: usize) -> usize {
        (if j < edges.len() {
            edges[j].a
        } else {
            edges[j - 1].b
        }) as usize
    }

    #[inline]
    fn ends(self, k: usize, particles: usize) -> (usize, usize) {
        (k, if k + 1 == particles { 0 } else { k + 1 })
    }

    fn for_incident(self, j: usize, m: usize, mut visit: impl FnMut(usize, f64)) {
        if j < m {
            visit(j, -1.0);
        }
        if j > 0 {
            visit(j - 1, 1.0);
        } else if self.closed {
            visit(m - 1, 1.0);
        }
    }

    fn symmetric_only(self) -> bool {
        false
    }

    fn solve(
        self,
        m: usize,
        direction: ConstraintDirection,
        keep_factor: bool,
        s: &mut IslandScratch,
    ) -> Result<(), SingularPivot> {
        chain_solve(m, self.closed, direction, keep_factor, s)
    }

    fn solve_many(self, m: usize, factors: &Factors, columns: &mut [f64], k: usize) {
        if self.closed && m >= 3 {
            factors.cyclic.solve_many(columns, k);
        } else {
            factors.open.solve_many(columns, k);
        }
    }
}

/// A tree or a graph.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GraphWalk<'a> {
    pub(crate) layout: &'a GraphLayout,
}

impl Walk for GraphWalk<'_> {
    fn particles(self, _edges: &[IslandEdge]) -> usize {
        self.layout.particles.len()
    }

    #[inline]
    fn particle(self, _edges: &[IslandEdge], j: usize) -> usize {
        self.layout.particles[j] as usize
    }

    #[inline]
    fn ends(self, k: usize, _particles: usize) -> (usize, usize) {
        let (a, b) = self.layout.ends[k];
        (a as usize, b as usize)
    }

    fn for_incident(self, j: usize, _m: usize, mut visit: impl FnMut(usize, f64)) {
        for &(k, sign) in self.layout.incident(j) {
            visit(k as usize, sign);
        }
    }

    fn symmetric_only(self) -> bool {
        true
    }

    fn solve(
        self,
        m: usize,
        _direction: ConstraintDirection,
        _keep_factor: bool,
        s: &mut IslandScratch,
    ) -> Result<(), SingularPivot> {
        graph_solve(m, self.layout, s)
    }

    fn solve_many(self, _m: usize, factors: &Factors, columns: &mut [f64], k: usize) {
        factors.sparse.solve_many(&self.layout.plan, columns, k);
    }
}
