//! Scene queries for gameplay: the first edge a ray meets (a grappling hook, a laser)
//! and the edge nearest a point (a hand reaching for a rope). Exact segment geometry
//! on the packed state, every edge tested: for the few queries a frame a game makes,
//! a pass over the edges costs less than keeping a structure for them up to date.

use bevy::math::DVec2;

use crate::model::Edge;
use crate::model::geometry::closest_on_segment;

/// Where a query met an edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeHit {
    /// The edge's index in the topology.
    pub edge: u32,
    /// The point met.
    pub point: DVec2,
    /// Where along the edge, from its first particle (0) to its second (1).
    pub alpha: f64,
    /// Along the ray (a ray cast) or from the point (a point query).
    pub distance: f64,
}

/// The first edge the ray from `origin` along `direction` (any length, not zero) meets
/// within `max_distance`, if any.
pub fn ray_cast(
    edges: &[Edge],
    position: &[DVec2],
    origin: DVec2,
    direction: DVec2,
    max_distance: f64,
) -> Option<EdgeHit> {
    let d = direction.normalize_or_zero();
    if d == DVec2::ZERO || !origin.is_finite() || max_distance.is_nan() {
        return None;
    }
    let mut best: Option<EdgeHit> = None;
    for (k, e) in edges.iter().enumerate() {
        let (a, b) = (position[e.a as usize], position[e.b as usize]);
        let s = b - a;
        let denominator = d.perp_dot(s);
        if denominator == 0.0 {
            // Parallel: a ray along the edge's own line meets its nearer end.
            if (a - origin).perp_dot(d) != 0.0 {
                continue;
            }
            for (end, alpha) in [(a, 0.0), (b, 1.0)] {
                let t = (end - origin).dot(d);
                if t >= 0.0 && t <= max_distance && best.is_none_or(|h| t < h.distance) {
                    best = Some(EdgeHit {
                        edge: k as u32,
                        point: end,
                        alpha,
                        distance: t,
                    });
                }
            }
            continue;
        }
        // origin + t d = a + u s.
        let t = (a - origin).perp_dot(s) / denominator;
        let u = (a - origin).perp_dot(d) / denominator;
        if (0.0..=1.0).contains(&u)
            && t >= 0.0
            && t <= max_distance
            && best.is_none_or(|h| t < h.distance)
        {
            best = Some(EdgeHit {
                edge: k as u32,
                point: a + u * s,
                alpha: u,
                distance: t,
            });
        }
    }
    best
}

/// The edge nearest `point` within `within`, if any.
pub fn nearest_edge(
    edges: &[Edge],
    position: &[DVec2],
    point: DVec2,
    within: f64,
) -> Option<EdgeHit> {
    let mut best: Option<EdgeHit> = None;
    for (k, e) in edges.iter().enumerate() {
        let (a, b) = (position[e.a as usize], position[e.b as usize]);
        let (alpha, distance) = closest_on_segment(point, a, b);
        if distance <= within && best.is_none_or(|h| distance < h.distance) {
            best = Some(EdgeHit {
                edge: k as u32,
                point: a + alpha * (b - a),
                alpha,
                distance,
            });
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan of random edges.
    fn scene(seed: u64) -> (Vec<Edge>, Vec<DVec2>) {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut position = Vec::new();
        let mut edges = Vec::new();
        for k in 0..40u32 {
            let a = DVec2::new(next(), next());
            position.push(a);
            position.push(a + 0.2 * DVec2::new(next() - 0.5, next() - 0.5));
            edges.push(Edge::new(2 * k, 2 * k + 1, 0.1));
        }
        (edges, position)
    }

    #[test]
    fn a_ray_cast_finds_the_first_edge_that_sampling_the_ray_finds() {
        for seed in 0..20 {
            let (edges, position) = scene(seed);
            let origin = DVec2::new(-0.1, 0.1 + 0.04 * seed as f64);
            let direction = DVec2::new(1.0, 0.3 - 0.03 * seed as f64);
            let hit = ray_cast(&edges, &position, origin, direction, 2.0);
            // Sampled: the first sample point within 1e-4 of any edge.
            let d = direction.normalize();
            let step = 2e-5;
            let sampled = (0..100_000).map(|i| i as f64 * step).find(|&t| {
                let p = origin + t * d;
                edges.iter().any(|e| {
                    closest_on_segment(p, position[e.a as usize], position[e.b as usize]).1 < 1e-4
                })
            });
            match (hit, sampled) {
                (Some(h), Some(t)) => {
                    assert!(
                        (h.distance - t).abs() < 1e-3,
                        "seed {seed}: {} against {t}",
                        h.distance
                    );
                    let e = &edges[h.edge as usize];
                    let on =
                        closest_on_segment(h.point, position[e.a as usize], position[e.b as usize]);
                    assert!(on.1 < 1e-12 && (on.0 - h.alpha).abs() < 1e-9);
                }
                (None, None) => {}
                other => panic!("seed {seed}: {other:?}"),
            }
        }
    }

    #[test]
    fn the_nearest_edge_is_the_nearest_of_all() {
        let (edges, position) = scene(3);
        for i in 0..50 {
            let p = DVec2::new(i as f64 / 50.0, 0.5);
            let hit = nearest_edge(&edges, &position, p, 1.0).unwrap();
            for e in &edges {
                let d = closest_on_segment(p, position[e.a as usize], position[e.b as usize]).1;
                assert!(hit.distance <= d);
            }
            assert!(nearest_edge(&edges, &position, p, 0.5 * hit.distance).is_none());
        }
        assert_eq!(
            ray_cast(&edges, &position, DVec2::ZERO, DVec2::ZERO, 1.0),
            None
        );
    }
}
