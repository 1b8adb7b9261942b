//! The invariant check: do any two edges that share no particle intersect?
//!
//! Run at the end of every step in checked mode; the count is the ground truth the
//! collision stage is judged by, so it uses exact orientation signs, not tolerances
//! ([`segments_intersect`]).

use std::ops::Range;

use bevy::math::DVec2;

use super::broad_phase::{Aabb, BroadPhase, BroadPhaseMethod};
use crate::model::Edge;
use crate::model::geometry::segments_intersect;
use crate::parallel::run_each;

/// How many edge pairs cross, and the smallest of them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Crossings {
    /// Pairs of edges sharing no particle that intersect.
    pub pairs: usize,
    /// The smallest such pair (edge indices, lexicographic), if any.
    pub first: Option<(u32, u32)>,
}

/// Edge pairs that share no particle and intersect at `position`. `pairs` is scratch
/// (brute force); the grid's pairs are tested on `threads` threads as they are found.
///
/// `reuse` is a grid built earlier (the collision stage's, over the step's swept
/// boxes): when its boxes, one per edge, still hold every edge's box at `position`, it
/// finds every pair the check needs and is counted on instead of building `broad`
/// (the second build was most of the check's cost). Either way the result is the
/// same: the count is exact and the first pair the smallest.
///
/// `among` picks the pairs counted (every pair, or by which edges moved this step;
/// see `collision::still`).
#[allow(clippy::too_many_arguments)]
pub fn count_crossings(
    edges: &[Edge],
    position: &[DVec2],
    broad: &mut BroadPhase,
    reuse: Option<&mut BroadPhase>,
    among: Among,
    method: BroadPhaseMethod,
    threads: usize,
    pairs: &mut Vec<(u32, u32)>,
) -> Crossings {
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
        let grid = match reuse {
            Some(grid) if covers(grid.boxes(), edges, position, threads) => grid,
            _ => {
                broad.build(edges, position, None, 0.0, threads);
                broad
            }
        };
        let (pairs, first) = match among {
            Among::All => grid.count_edge_pairs(threads, None, crossed),
            Among::Moving(moving) => grid.count_edge_pairs(threads, Some(moving), crossed),
            Among::Still(moving) => grid.count_edge_pairs(threads, None, |j, k| {
                !moving[j as usize] && !moving[k as usize] && crossed(j, k)
            }),
        };
        return Crossings { pairs, first };
    }
    broad.build(edges, position, None, 0.0, threads);
    pairs.clear();
    broad.edge_edge_pairs(method, crossed, pairs);
    Crossings {
        pairs: pairs.len(),
        first: pairs.iter().min().copied(),
    }
}

/// Which pairs of edges [`count_crossings`] counts.
#[derive(Clone, Copy, Debug)]
pub enum Among<'a> {
    /// Every pair.
    All,
    /// Pairs with at least one edge marked moving.
    Moving(&'a [bool]),
    /// Pairs of two edges not marked moving (the grid only).
    Still(&'a [bool]),
}

/// Below this many edges the cover test runs on one thread.
const PARALLEL_COVER: usize = 16_384;

/// Whether `boxes` has one box per edge holding both of its ends at `position` (a NaN
/// end is held by none). On one thread it allocates nothing.
pub fn covers(boxes: &[Aabb], edges: &[Edge], position: &[DVec2], threads: usize) -> bool {
    if boxes.len() != edges.len() {
        return false;
    }
    let holds = |b: &Aabb, p: DVec2| b.min.cmple(p).all() && p.cmple(b.max).all();
    let inside = |range: Range<usize>| {
        let (edges, boxes) = (&edges[range.clone()], &boxes[range]);
        edges
            .iter()
            .zip(boxes)
            .all(|(e, b)| holds(b, position[e.a as usize]) && holds(b, position[e.b as usize]))
    };
    let n = edges.len();
    if threads <= 1 || n < PARALLEL_COVER {
        return inside(0..n);
    }
    let parts: Vec<Range<usize>> = (0..threads)
        .map(|t| n * t / threads..n * (t + 1) / threads)
        .collect();
    run_each(parts, |_, range| inside(range))
        .into_iter()
        .all(|held| held)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// Random walks of 20 edges in the unit square (crossing each other often), their
    /// displacements over a step, and a grid over the swept boxes inflated by 4 mm.
    fn swept_scene(rng: &mut StdRng) -> (Vec<Edge>, Vec<DVec2>, Vec<DVec2>, BroadPhase) {
        let (mut edges, mut position, mut displacement) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..1200 {
            let mut x = DVec2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
            let first = position.len() as u32;
            for i in 0..21 {
                position.push(x);
                let d = rng.random_range(0.0..0.02);
                displacement.push(d * DVec2::from_angle(rng.random_range(0.0..6.3)));
                x += 0.01 * DVec2::from_angle(rng.random_range(0.0..6.3));
                if i > 0 {
                    edges.push(Edge::new(first + i - 1, first + i, 0.01));
                }
            }
        }
        let mut grid = BroadPhase::default();
        grid.build(&edges, &position, Some(&displacement), 0.004, 1);
        (edges, position, displacement, grid)
    }

    fn count(
        edges: &[Edge],
        position: &[DVec2],
        reuse: Option<&mut BroadPhase>,
        method: BroadPhaseMethod,
        threads: usize,
    ) -> Crossings {
        let mut own = BroadPhase::default();
        count_crossings(
            edges,
            position,
            &mut own,
            reuse,
            Among::All,
            method,
            threads,
            &mut Vec::new(),
        )
    }

    #[test]
    fn a_covering_grid_counts_what_brute_force_and_an_own_grid_count() {
        let mut rng = StdRng::seed_from_u64(11);
        let (edges, start, displacement, mut grid) = swept_scene(&mut rng);
        // Ends somewhere along the sweep, pushed by up to the margin: still covered.
        let end: Vec<DVec2> = (start.iter().zip(&displacement))
            .map(|(&x, &d)| {
                let push = DVec2::new(rng.random_range(-0.0039..0.0039), 0.0);
                x + rng.random_range(0.0..1.0) * d + push
            })
            .collect();
        assert!(covers(grid.boxes(), &edges, &end, 1));
        let brute = count(&edges, &end, None, BroadPhaseMethod::BruteForce, 1);
        assert!(brute.pairs > 100, "{brute:?}");
        assert_eq!(count(&edges, &end, None, BroadPhaseMethod::Grid, 1), brute);
        for threads in [1, 2, 3] {
            let reused = count(
                &edges,
                &end,
                Some(&mut grid),
                BroadPhaseMethod::Grid,
                threads,
            );
            assert_eq!(reused, brute, "{threads} threads");
        }
    }

    #[test]
    fn a_grid_that_no_longer_covers_is_not_counted_on() {
        let mut rng = StdRng::seed_from_u64(12);
        let (edges, start, _, mut grid) = swept_scene(&mut rng);
        let mut end = start.clone();
        // One end dragged across the square: its edges now cross others the grid has
        // never seen them near.
        end[10] = DVec2::new(1.2, -0.2);
        end[30] = DVec2::new(-0.2, 1.2);
        assert!(!covers(grid.boxes(), &edges, &end, 2));
        let brute = count(&edges, &end, None, BroadPhaseMethod::BruteForce, 1);
        assert!(brute.pairs > count(&edges, &start, None, BroadPhaseMethod::BruteForce, 1).pairs);
        assert_eq!(
            count(&edges, &end, Some(&mut grid), BroadPhaseMethod::Grid, 2),
            brute
        );
        // A NaN end, and a grid over other edges, are never covered.
        end[10] = DVec2::NAN;
        assert!(!covers(grid.boxes(), &edges, &end, 1));
        assert!(!covers(grid.boxes(), &edges[1..], &start[..], 1));
    }
}
