//! The invariant check: do any two edges that share no particle intersect?
//!
//! Run at the end of every step in checked mode; the count is the ground truth the
//! collision stage is judged by, so it uses exact orientation signs, not tolerances.

use bevy::math::DVec2;

use super::broad_phase::{BroadPhase, BroadPhaseMethod};
use crate::topology::Edge;

/// Orientation of c relative to the directed line a→b: positive to the left.
fn orientation(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether segments a–b and c–d intersect, touching included.
pub fn segments_intersect(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (o1, o2) = (orientation(a, b, c), orientation(a, b, d));
    let (o3, o4) = (orientation(c, d, a), orientation(c, d, b));
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return true;
    }
    let within = |p: DVec2, q: DVec2, x: DVec2| {
        x.x >= p.x.min(q.x) && x.x <= p.x.max(q.x) && x.y >= p.y.min(q.y) && x.y <= p.y.max(q.y)
    };
    (o1 == 0.0 && within(a, b, c))
        || (o2 == 0.0 && within(a, b, d))
        || (o3 == 0.0 && within(c, d, a))
        || (o4 == 0.0 && within(c, d, b))
}

/// Edge pairs that share no particle and intersect at `position`. `pairs` is scratch.
pub fn count_crossings(
    edges: &[Edge],
    position: &[DVec2],
    broad: &mut BroadPhase,
    method: BroadPhaseMethod,
    pairs: &mut Vec<(u32, u32)>,
) -> usize {
    broad.build(edges, position, None, 0.0);
    pairs.clear();
    let share = |j: u32, k: u32| {
        let (e, f) = (&edges[j as usize], &edges[k as usize]);
        e.a == f.a || e.a == f.b || e.b == f.a || e.b == f.b
    };
    broad.edge_edge_pairs(method, |j, k| !share(j, k), pairs);
    pairs
        .iter()
        .filter(|&&(j, k)| {
            let (e, f) = (&edges[j as usize], &edges[k as usize]);
            segments_intersect(
                position[e.a as usize],
                position[e.b as usize],
                position[f.a as usize],
                position[f.b as usize],
            )
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_touching_and_disjoint_segments() {
        let p = |x, y| DVec2::new(x, y);
        assert!(segments_intersect(
            p(0.0, 0.0),
            p(1.0, 1.0),
            p(0.0, 1.0),
            p(1.0, 0.0)
        ));
        assert!(segments_intersect(
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(0.5, 0.0),
            p(0.5, 1.0)
        ));
        assert!(!segments_intersect(
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(0.5, 1e-12),
            p(0.5, 1.0)
        ));
        assert!(!segments_intersect(
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(2.0, 0.0),
            p(3.0, 0.0)
        ));
        assert!(segments_intersect(
            p(0.0, 0.0),
            p(2.0, 0.0),
            p(1.0, 0.0),
            p(3.0, 0.0)
        ));
    }
}
