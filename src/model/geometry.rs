//! Plane geometry shared by the stages: turning angles, closest points on segments and
//! exact segment intersection.

use std::f64::consts::{PI, TAU};

use bevy::math::DVec2;

/// Signed turning angle (radians, counter-clockwise positive) from edge `incoming` to
/// edge `outgoing`.
pub fn turning_angle(incoming: DVec2, outgoing: DVec2) -> f64 {
    incoming.perp_dot(outgoing).atan2(incoming.dot(outgoing))
}

/// Turning angles at every bending vertex of the polyline through `points`.
pub fn turning_angles(points: &[DVec2], closed: bool) -> Vec<f64> {
    let n = points.len();
    (0..super::bend_count(n, closed))
        .map(|k| {
            let s = if closed { k } else { k + 1 };
            let prev = points[(s + n - 1) % n];
            let next = points[(s + 1) % n];
            turning_angle(points[s] - prev, next - points[s])
        })
        .collect()
}

/// The angle in (−π, π].
pub fn wrap_angle(angle: f64) -> f64 {
    let wrapped = (angle + PI).rem_euclid(TAU) - PI;
    if wrapped == -PI { PI } else { wrapped }
}

/// Closest point of segment q–r to p: its α in [0, 1] and the distance.
pub fn closest_on_segment(p: DVec2, q: DVec2, r: DVec2) -> (f64, f64) {
    let edge = r - q;
    let length_squared = edge.length_squared();
    let alpha = if length_squared > 0.0 {
        ((p - q).dot(edge) / length_squared).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (alpha, p.distance(q + alpha * edge))
}

/// Distance between segments a–b and c–d (0 if they intersect).
pub fn segment_distance(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> f64 {
    if segments_intersect(a, b, c, d) {
        return 0.0;
    }
    [
        closest_on_segment(a, c, d).1,
        closest_on_segment(b, c, d).1,
        closest_on_segment(c, a, b).1,
        closest_on_segment(d, a, b).1,
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// Orientation of c relative to the directed line a→b: positive to the left.
fn orientation(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether segments a–b and c–d intersect, touching included. Exact orientation signs,
/// no tolerance: this is the ground truth the crossing check counts.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_wrap_into_half_open_interval() {
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert_eq!(wrap_angle(-PI), PI);
        assert_eq!(wrap_angle(0.25), 0.25);
    }

    #[test]
    fn a_triangle_turns_by_a_third_of_a_turn_at_each_corner() {
        let tri = [DVec2::ZERO, DVec2::X, DVec2::new(0.5, 3f64.sqrt() / 2.0)];
        for a in turning_angles(&tri, true) {
            assert!((a - TAU / 3.0).abs() < 1e-12);
        }
    }

    #[test]
    fn segment_distance_agrees_with_sampling() {
        let p = |x, y| DVec2::new(x, y);
        let cases = [
            (p(0.0, 0.0), p(1.0, 0.0), p(0.5, 0.3), p(0.5, 2.0), 0.3),
            (p(0.0, 0.0), p(1.0, 0.0), p(0.5, -1.0), p(0.5, 1.0), 0.0),
            (p(0.0, 0.0), p(1.0, 0.0), p(2.0, 0.0), p(3.0, 0.0), 1.0),
            (
                p(0.0, 0.0),
                p(1.0, 1.0),
                p(2.0, 0.0),
                p(3.0, -1.0),
                2f64.sqrt(),
            ),
        ];
        for (a, b, c, d, expected) in cases {
            let sampled = (0..=400)
                .flat_map(|i| (0..=400).map(move |j| (i as f64 / 400.0, j as f64 / 400.0)))
                .map(|(s, t)| a.lerp(b, s).distance(c.lerp(d, t)))
                .fold(f64::INFINITY, f64::min);
            let distance = segment_distance(a, b, c, d);
            assert!(
                (distance - expected).abs() < 1e-12,
                "{distance} vs {expected}"
            );
            assert!(distance <= sampled + 1e-12 && sampled - distance < 5e-3);
        }
    }

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
