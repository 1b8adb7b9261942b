//! Clearance: which points lie closer than the thickness to an edge they are not an end
//! of. A state with such a pair is one the proximity pass starts by pushing apart —
//! for an initial state, usually a mistake in the scene (a strand laid on a wall, two
//! strands drawn through each other's cushion).

use bevy::math::DVec2;

use super::broad_phase::{BroadPhase, BroadPhaseMethod};
use super::exempt::Exempt;
use crate::model::Edge;
use crate::model::geometry::closest_on_segment;

/// A point closer than the thickness to an edge it is not an end of.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    /// The point's packed index.
    pub point: u32,
    /// The edge's index.
    pub edge: u32,
    /// Their distance.
    pub distance: f64,
}

/// Every point–edge pair closer than `thickness`, in point order, leaving out the
/// point's own edges, the edges of its strand within a thickness of it along the
/// strand ([`Exempt`]) and the pairs of three pinned particles (which nothing pushes
/// apart), exactly the pairs the collision stage would consider.
pub fn overlaps(
    edges: &[Edge],
    position: &[DVec2],
    inverse_mass: &[f64],
    thickness: f64,
    broad: &mut BroadPhase,
    method: BroadPhaseMethod,
    threads: usize,
) -> Vec<Overlap> {
    broad.build(edges, position, None, thickness, threads);
    let still = vec![DVec2::ZERO; position.len()];
    let mut exempt = Exempt::default();
    exempt.build(edges, position.len(), thickness);
    let keep = |p: u32, k: u32| {
        let e = &edges[k as usize];
        let w = |i: u32| inverse_mass[i as usize];
        e.a != p && e.b != p && (w(p) > 0.0 || w(e.a) > 0.0 || w(e.b) > 0.0) && !exempt.exempt(p, e)
    };
    let mut pairs = Vec::new();
    broad.point_edge_pairs(method, threads, position, &still, keep, &mut pairs);
    pairs
        .into_iter()
        .filter_map(|(p, k)| {
            let e = &edges[k as usize];
            let (_, distance) = closest_on_segment(
                position[p as usize],
                position[e.a as usize],
                position[e.b as usize],
            );
            (distance < thickness).then_some(Overlap {
                point: p,
                edge: k,
                distance,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlaps_match_every_pair_tested_by_hand() {
        // A comb of short vertical edges and points scattered among them.
        let mut position = Vec::new();
        let mut edges = Vec::new();
        for i in 0..20 {
            let x = i as f64 * 0.05;
            position.push(DVec2::new(x, 0.0));
            position.push(DVec2::new(x, 0.1));
            let a = 2 * i as u32;
            edges.push(Edge::new(a, a + 1, 0.1));
        }
        let first_point = position.len();
        let mut seed = 7u64;
        for _ in 0..300 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (seed >> 11) as f64 / (1u64 << 53) as f64;
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let v = (seed >> 11) as f64 / (1u64 << 53) as f64;
            position.push(DVec2::new(u * 1.0, v * 0.12 - 0.01));
        }
        let mut inverse_mass = vec![1.0; position.len()];
        // The first edge and a point on it are pinned: that pair is left out.
        inverse_mass[0] = 0.0;
        inverse_mass[1] = 0.0;
        position[first_point] = DVec2::new(0.0, 0.05);
        inverse_mass[first_point] = 0.0;
        let h = 0.004;
        let mut expected = Vec::new();
        for p in 0..position.len() as u32 {
            for (k, e) in edges.iter().enumerate() {
                let pinned = [p, e.a, e.b]
                    .iter()
                    .all(|&i| inverse_mass[i as usize] == 0.0);
                if e.a == p || e.b == p || pinned {
                    continue;
                }
                let (_, d) = closest_on_segment(
                    position[p as usize],
                    position[e.a as usize],
                    position[e.b as usize],
                );
                if d < h {
                    expected.push((p, k as u32));
                }
            }
        }
        assert!(
            expected.len() > 5,
            "too few overlaps to test: {}",
            expected.len()
        );
        for method in [BroadPhaseMethod::Grid, BroadPhaseMethod::BruteForce] {
            for threads in [1, 2] {
                let mut broad = BroadPhase::default();
                let mut found: Vec<(u32, u32)> = overlaps(
                    &edges,
                    &position,
                    &inverse_mass,
                    h,
                    &mut broad,
                    method,
                    threads,
                )
                .iter()
                .map(|o| (o.point, o.edge))
                .collect();
                found.sort_unstable();
                assert_eq!(found, expected, "{method:?}, {threads} threads");
            }
        }
    }
}
