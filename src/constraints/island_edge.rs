//! An edge as an island sees it: its two particles in the island's orientation.

use bevy::math::DVec2;

/// An edge of an island, oriented along the island's order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IslandEdge {
    /// Start particle (packed index).
    pub a: u32,
    /// End particle (packed index).
    pub b: u32,
    /// Rest length.
    pub rest_length: f64,
    /// Index in the topology's edge list.
    pub edge: u32,
}

impl IslandEdge {
    /// Edges joining `pairs` of `points`, each at its current length, numbered in order
    /// (for kernels used without a topology: tests, benchmarks, tools).
    pub fn between(points: &[DVec2], pairs: &[(u32, u32)]) -> Vec<IslandEdge> {
        pairs
            .iter()
            .enumerate()
            .map(|(k, &(a, b))| IslandEdge {
                a,
                b,
                rest_length: points[a as usize].distance(points[b as usize]),
                edge: k as u32,
            })
            .collect()
    }

    /// The edges of a chain through `points`, each at its current length: a path, or a
    /// loop when `closed`.
    pub fn chain(points: &[DVec2], closed: bool) -> Vec<IslandEdge> {
        let n = points.len() as u32;
        let m = if closed { n } else { n.saturating_sub(1) };
        let pairs: Vec<(u32, u32)> = (0..m).map(|k| (k, (k + 1) % n)).collect();
        Self::between(points, &pairs)
    }
}
