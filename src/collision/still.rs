//! The broad phase where most of the world stands still (a sleeping pile, walls).
//!
//! A particle that is pinned and not moving this step ("still") cannot be brought into
//! contact by its own motion, and two still edges cannot come to cross. So the pairs a
//! step needs are those of every moving point against every edge, and of every still
//! point against the moving edges only; and the crossing check needs only the pairs
//! with a moving edge. Querying from what moves makes a settled pile cost what its
//! moving neighbours touch, not its size.

use bevy::math::DVec2;

use super::broad_phase::BroadPhase;
use crate::model::Edge;

/// Whether particle `i` stands still this step: pinned (or asleep) and not moving.
pub fn is_still(inverse_mass: &[f64], displacement: &[DVec2], i: usize) -> bool {
    inverse_mass[i] == 0.0 && displacement[i] == DVec2::ZERO
}

/// Worth querying from the moving side only once at least this share of particles
/// stands still (below it, the usual all-points query is as fast and keeps the
/// pairs' order as it always was).
pub const STILL_SHARE: f64 = 0.25;

/// Whether `still` of `n` particles are enough to query from the moving side.
pub fn mostly_still(still: usize, n: usize) -> bool {
    n > 0 && still as f64 >= STILL_SHARE * n as f64
}

impl BroadPhase {
    /// As [`BroadPhase::point_edge_pairs`] with the grid method, for the listed points
    /// only (ascending): the same pairs for each of them in the same order.
    pub fn listed_point_edge_pairs(
        &mut self,
        threads: usize,
        points: &[u32],
        position: &[DVec2],
        displacement: &[DVec2],
        keep: impl Fn(u32, u32) -> bool + Sync,
        pairs: &mut Vec<(u32, u32)>,
    ) {
        let point = |k: usize| points[k] as usize;
        let n = points.len();
        self.query_shares(threads, n, point, position, displacement, keep, pairs);
    }
}

/// The split of one broad-phase search into moving and still.
#[derive(Clone, Debug, Default)]
pub struct StillScratch {
    /// The grid of the moving edges.
    pub broad: BroadPhase,
    /// The moving edges...
    pub edges: Vec<Edge>,
    /// ...and their indices among every edge.
    pub edge_index: Vec<u32>,
    /// The particles that move, ascending.
    pub moving_points: Vec<u32>,
    /// The particles that stand still, ascending.
    pub still_points: Vec<u32>,
    /// The still points' pairs.
    pub pairs: Vec<(u32, u32)>,
    /// Room for merging.
    pub merged: Vec<(u32, u32)>,
}

impl StillScratch {
    /// Sort the particles into moving and still and list the moving edges; `false`
    /// (and nothing listed) when fewer than [`STILL_SHARE`] stand still.
    pub fn split(&mut self, edges: &[Edge], inverse_mass: &[f64], displacement: &[DVec2]) -> bool {
        let n = displacement.len().min(inverse_mass.len());
        self.moving_points.clear();
        self.still_points.clear();
        for i in 0..n as u32 {
            if is_still(inverse_mass, displacement, i as usize) {
                self.still_points.push(i);
            } else {
                self.moving_points.push(i);
            }
        }
        if !mostly_still(self.still_points.len(), n) {
            return false;
        }
        self.edges.clear();
        self.edge_index.clear();
        for (k, e) in edges.iter().enumerate() {
            let moves = |i: u32| !is_still(inverse_mass, displacement, i as usize);
            if moves(e.a) || moves(e.b) {
                self.edges.push(*e);
                self.edge_index.push(k as u32);
            }
        }
        true
    }
}

/// Merge `other` into `pairs`, both in point order (each point's pairs from one of
/// them), keeping point order.
pub fn merge_by_point(
    pairs: &mut Vec<(u32, u32)>,
    other: &[(u32, u32)],
    merged: &mut Vec<(u32, u32)>,
) {
    if other.is_empty() {
        return;
    }
    merged.clear();
    let (mut i, mut j) = (0, 0);
    while i < pairs.len() || j < other.len() {
        let take_first = j == other.len() || (i < pairs.len() && pairs[i].0 <= other[j].0);
        if take_first {
            merged.push(pairs[i]);
            i += 1;
        } else {
            merged.push(other[j]);
            j += 1;
        }
    }
    std::mem::swap(pairs, merged);
}

/// Which edges move this step: those with an end that is not still.
pub fn moving_edges(edges: &[Edge], still: &[bool], moving: &mut Vec<bool>) {
    moving.clear();
    moving.extend(
        edges
            .iter()
            .map(|e| !(still[e.a as usize] && still[e.b as usize])),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::broad_phase::BroadPhaseMethod;
    use crate::model::geometry::segments_intersect;

    /// A zigzag of edges over a strip, with every third particle still.
    fn strip() -> (Vec<Edge>, Vec<DVec2>, Vec<bool>) {
        let mut position = Vec::new();
        let mut edges = Vec::new();
        for i in 0..60u32 {
            let x = 0.01 * f64::from(i % 20);
            let y = 0.013 * f64::from(i / 20) + if (i + i / 20) % 2 == 0 { 0.0 } else { 0.02 };
            position.push(DVec2::new(x + 0.003 * f64::from(i / 20), y));
            if i % 20 != 0 {
                edges.push(Edge {
                    a: i - 1,
                    b: i,
                    rest_length: 0.02,
                    strand: i / 20,
                    is_static: false,
                    constrained: true,
                    spring: false,
                    stiffness: 0.0,
                    damping: 0.0,
                    solid: false,
                });
            }
        }
        let still = (0..60).map(|i| i % 3 == 0 || i >= 40).collect();
        (edges, position, still)
    }

    #[test]
    fn moving_pairs_are_every_pair_with_a_moving_edge() {
        let (edges, position, still) = strip();
        let mut moving = Vec::new();
        moving_edges(&edges, &still, &mut moving);
        let crossed = |j: u32, k: u32| {
            let (e, f) = (&edges[j as usize], &edges[k as usize]);
            !e.shares_particle(f)
                && segments_intersect(
                    position[e.a as usize],
                    position[e.b as usize],
                    position[f.a as usize],
                    position[f.b as usize],
                )
        };
        let mut all = Vec::new();
        for j in 0..edges.len() as u32 {
            for k in j + 1..edges.len() as u32 {
                if (moving[j as usize] || moving[k as usize]) && crossed(j, k) {
                    all.push((j, k));
                }
            }
        }
        assert!(!all.is_empty(), "the strip has crossings to find");
        for threads in [1, 2] {
            let mut broad = BroadPhase::default();
            broad.build(&edges, &position, None, 0.0, threads);
            let (count, first) = broad.count_edge_pairs(threads, Some(&moving), crossed);
            assert_eq!((count, first), (all.len(), all.first().copied()));
        }
    }

    #[test]
    fn listed_points_get_the_pairs_of_a_full_query() {
        let (edges, position, still) = strip();
        let displacement: Vec<DVec2> = (0..position.len())
            .map(|i| DVec2::new(0.0, -0.004 * f64::from(i as u32 % 5)))
            .collect();
        let mut broad = BroadPhase::default();
        broad.build(&edges, &position, Some(&displacement), 0.004, 1);
        let keep = |p: u32, k: u32| edges[k as usize].a != p && edges[k as usize].b != p;
        let mut full = Vec::new();
        broad.point_edge_pairs(
            BroadPhaseMethod::Grid,
            1,
            &position,
            &displacement,
            keep,
            &mut full,
        );
        let listed: Vec<u32> = (0..position.len() as u32)
            .filter(|&i| !still[i as usize])
            .collect();
        let mut some = Vec::new();
        broad.listed_point_edge_pairs(1, &listed, &position, &displacement, keep, &mut some);
        full.retain(|&(p, _)| !still[p as usize]);
        assert!(!full.is_empty());
        assert_eq!(some, full);
    }
}
