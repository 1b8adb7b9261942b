//! The invariant check: do any two edges that share no particle intersect?
//!
//! Run at the end of every step in checked mode; the count is the ground truth the
//! collision stage is judged by, so it uses exact orientation signs, not tolerances
//! ([`segments_intersect`]).

use bevy::math::DVec2;

use super::broad_phase::{BroadPhase, BroadPhaseMethod};
use crate::model::Edge;
use crate::model::geometry::segments_intersect;

/// How many edge pairs cross, and the first of them in the broad phase's order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Crossings {
    /// Pairs of edges sharing no particle that intersect.
    pub pairs: usize,
    /// The first such pair (edge indices), if any.
    pub first: Option<(u32, u32)>,
}

/// Edge pairs that share no particle and intersect at `position`. `pairs` is scratch
/// (brute force); the grid's pairs are tested on `threads` threads as they are found.
pub fn count_crossings(
    edges: &[Edge],
    position: &[DVec2],
    broad: &mut BroadPhase,
    method: BroadPhaseMethod,
    threads: usize,
    pairs: &mut Vec<(u32, u32)>,
) -> Crossings {
    broad.build(edges, position, None, 0.0, threads);
    let crossed = |j: u32, k: u32| {
        let (e, f) = (&edges[j as usize], &edges[k as usize]);
        // Walls' and bodies' edges never meet each other (see `Edge::solid`).
        let apart = e.shares_particle(f) || (e.solid && f.solid);
        !apart
            && segments_intersect(
                position[e.a as usize],
                position[e.b as usize],
                position[f.a as usize],
                position[f.b as usize],
            )
    };
    if method == BroadPhaseMethod::Grid {
        let (pairs, first) = broad.count_edge_pairs(threads, crossed);
        return Crossings { pairs, first };
    }
    pairs.clear();
    broad.edge_edge_pairs(method, crossed, pairs);
    Crossings {
        pairs: pairs.len(),
        first: pairs.first().copied(),
    }
}
