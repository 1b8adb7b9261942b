//! Continuous point–edge collision detection in 2D.
//!
//! Two moving segments can only start to cross when a vertex of one touches the
//! other, so point–edge tests are complete. With every point moving linearly over the
//! step (τ ∈ [0, 1]), point p and edge (q, r) are collinear when
//! `(q(τ) − p(τ)) × (r(τ) − p(τ)) = 0`, a quadratic in τ. Its roots in [0, 1], in
//! order, are candidate contacts; the first whose barycentric coordinate α of p along
//! qr lies in [0, 1] is the time of impact. Degenerate cases (vanishing leading
//! coefficient, motion that keeps all three collinear, touching at an endpoint) are
//! handled explicitly, and the tests are slightly conservative: a near miss by a few
//! ulps counts as a hit.

use bevy::math::DVec2;

/// A contact found over the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointEdgeHit {
    /// Fraction of the step at which the point touches the edge, in [0, 1].
    pub time: f64,
    /// Where along the edge: the contact point is `(1 − α) q + α r`, α in [0, 1].
    pub alpha: f64,
    /// Unit normal of the edge at the time of impact, on the side the point came from.
    pub normal: DVec2,
    /// Whether the point ends the step on the other side of the edge's line, by the
    /// orientation test of the crossing check on the same end positions.
    pub crosses: bool,
}

/// Orientation of `p` relative to the directed line q→r: the crossing check's test
/// ([`segments_intersect`](crate::model::geometry::segments_intersect)), term for term.
fn side(p: DVec2, q: DVec2, r: DVec2) -> f64 {
    (r - q).perp_dot(p - q)
}

/// Relative tolerance of the degenerate-case tests and of α's range.
const EPS: f64 = 1e-12;

/// Time of impact of point `p` (moving by `dp` over the step) with edge `q`–`r`
/// (moving by `dq`, `dr`), if they touch during the step.
pub fn point_edge_time_of_impact(
    p: DVec2,
    dp: DVec2,
    q: DVec2,
    dq: DVec2,
    r: DVec2,
    dr: DVec2,
) -> Option<PointEdgeHit> {
    if !boxes_meet(p, dp, q, dq, r, dr) {
        return None;
    }
    time_of_impact(p, dp, q, dq, r, dr)
}

/// [`point_edge_time_of_impact`] past the boxes' test.
fn time_of_impact(
    p: DVec2,
    dp: DVec2,
    q: DVec2,
    dq: DVec2,
    r: DVec2,
    dr: DVec2,
) -> Option<PointEdgeHit> {
    let (a0, a1) = (q - p, dq - dp);
    let (b0, b1) = (r - p, dr - dp);
    let quadratic = a1.perp_dot(b1);
    let linear = a0.perp_dot(b1) + a1.perp_dot(b0);
    let constant = a0.perp_dot(b0);
    let scale = (a0.length() + a1.length()) * (b0.length() + b1.length());
    if scale == 0.0 {
        return None; // all three points coincide and stay so: nothing to collide with
    }
    let tiny = EPS * scale;

    let at = |t: f64| hit_at(t, p, dp, q, dq, r, dr);
    let mut roots = [f64::NAN; 2];
    if quadratic.abs() <= tiny {
        if linear.abs() > tiny {
            roots[0] = -constant / linear;
        } else if constant.abs() <= tiny {
            // Collinear throughout: the point slides along the edge's line and hits
            // the edge where it reaches an endpoint, or at once if already on it.
            return collinear_contact(p, dp, q, dq, r, dr);
        }
        // Otherwise the motion is parallel to the line as far as the coefficients
        // can tell; the sign test below still catches a crossing at smaller scales.
    } else {
        let discriminant = linear * linear - 4.0 * quadratic * constant;
        if discriminant < 0.0 {
            if discriminant >= -EPS * (linear * linear).max(tiny * tiny) {
                roots[0] = -linear / (2.0 * quadratic); // grazing: a double root
            }
        } else {
            // The stable pair of roots: no cancellation in either.
            let s = -0.5 * (linear + linear.signum() * discriminant.sqrt());
            roots = [s / quadratic, if s != 0.0 { constant / s } else { 0.0 }];
            if roots[0] > roots[1] {
                roots.swap(0, 1);
            }
        }
    }
    // The sides at the start and at the end of the step, computed as the crossing check
    // computes them on the positions the Integrate stage will produce (`x + d`): a
    // point that ends across the line has crossed it, whatever the tolerances above
    // made of the motion, and it is reported as crossing exactly when the check would
    // count it.
    let (start, end) = (side(p, q, r), side(p + dp, q + dq, r + dr));
    let crosses = (start > 0.0 && end <= 0.0) || (start < 0.0 && end >= 0.0);
    let found = roots
        .into_iter()
        .filter(|t| t.is_finite() && *t >= -EPS && *t <= 1.0 + EPS)
        .find_map(|t| at(t.clamp(0.0, 1.0)));
    if let Some(hit) = found {
        return Some(PointEdgeHit { crosses, ..hit });
    }
    if crosses {
        // Find where by bisection on the sign of the same orientation along the motion.
        let along = |t: f64| side(p + t * dp, q + t * dq, r + t * dr);
        let (mut low, mut high) = (0.0, 1.0);
        for _ in 0..64 {
            let middle = 0.5 * (low + high);
            if (along(middle) > 0.0) == (start > 0.0) {
                low = middle;
            } else {
                high = middle;
            }
        }
        return at(high).map(|hit| PointEdgeHit {
            crosses: true,
            ..hit
        });
    }
    None
}

/// Whether the box of the point's path meets the box of the edge's sweep, widened by
/// far more than the tolerances above: a point that never enters the edge's box
/// cannot touch it. Most pairs a broad phase hands over (boxes widened by a
/// thickness) end here, before the quadratic.
fn boxes_meet(p: DVec2, dp: DVec2, q: DVec2, dq: DVec2, r: DVec2, dr: DVec2) -> bool {
    let (p1, q1, r1) = (p + dp, q + dq, r + dr);
    let (low, high) = (p.min(p1), p.max(p1));
    let (edge_low, edge_high) = (q.min(q1).min(r).min(r1), q.max(q1).max(r).max(r1));
    let slack = 1e-9 * ((high - low) + (edge_high - edge_low)).max_element();
    low.cmple(edge_high + slack).all() && edge_low.cmple(high + slack).all()
}

/// The contact at time `t`, if p then lies on the edge (α in [0, 1] up to tolerance).
fn hit_at(
    t: f64,
    p: DVec2,
    dp: DVec2,
    q: DVec2,
    dq: DVec2,
    r: DVec2,
    dr: DVec2,
) -> Option<PointEdgeHit> {
    let (pt, qt, rt) = (p + t * dp, q + t * dq, r + t * dr);
    let edge = rt - qt;
    let length_squared = edge.length_squared();
    let (alpha, normal) = if length_squared > 0.0 {
        let alpha = (pt - qt).dot(edge) / length_squared;
        if !(-EPS..=1.0 + EPS).contains(&alpha) {
            return None;
        }
        (alpha.clamp(0.0, 1.0), edge.perp() / length_squared.sqrt())
    } else {
        // The edge has shrunk to a point: a hit only if p is exactly there.
        if pt != qt {
            return None;
        }
        (0.0, (p - q).normalize_or(DVec2::Y))
    };
    Some(PointEdgeHit {
        time: t,
        alpha,
        normal: orient_normal(normal, p, q, r, dp, dq, dr, alpha),
        crosses: false,
    })
}

/// Flip `normal` to the side p started on; if it started on the line, against the
/// relative approach.
#[allow(clippy::too_many_arguments)]
fn orient_normal(
    normal: DVec2,
    p: DVec2,
    q: DVec2,
    r: DVec2,
    dp: DVec2,
    dq: DVec2,
    dr: DVec2,
    alpha: f64,
) -> DVec2 {
    // Differences from q, which lies close to p, carry no rounding of the coordinates
    // themselves: the side is resolved down to gaps far below the pair's size.
    let start_side = normal.dot((p - q) - alpha * (r - q));
    let side = if start_side != 0.0 {
        start_side
    } else {
        -normal.dot((dp - dq) - alpha * (dr - dq))
    };
    if side < 0.0 { -normal } else { normal }
}

/// Contact of a point moving along the line of a (moving) edge: the first time its
/// coordinate along the line enters the edge's interval.
fn collinear_contact(
    p: DVec2,
    dp: DVec2,
    q: DVec2,
    dq: DVec2,
    r: DVec2,
    dr: DVec2,
) -> Option<PointEdgeHit> {
    let axis = (r - q)
        .try_normalize()
        .or((r + dr - q - dq).try_normalize())?;
    let coordinate = |x: DVec2| x.dot(axis);
    // Signed offsets of p from each endpoint along the line, linear in τ.
    let from_q = (coordinate(p - q), coordinate(dp - dq));
    let from_r = (coordinate(p - r), coordinate(dp - dr));
    let inside = |t: f64| {
        let (sq, sr) = (from_q.0 + t * from_q.1, from_r.0 + t * from_r.1);
        sq * sr <= 0.0
    };
    let mut candidates = [0.0, f64::NAN, f64::NAN];
    for (slot, (offset, rate)) in [from_q, from_r].into_iter().enumerate() {
        if rate != 0.0 {
            candidates[slot + 1] = -offset / rate;
        }
    }
    candidates.sort_by(f64::total_cmp);
    candidates
        .into_iter()
        .filter(|t| t.is_finite() && (0.0..=1.0).contains(t))
        .find(|&t| inside(t))
        .and_then(|t| hit_at(t, p, dp, q, dq, r, dr))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::geometry::closest_on_segment;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    fn hit(p: DVec2, dp: DVec2, q: DVec2, dq: DVec2, r: DVec2, dr: DVec2) -> Option<PointEdgeHit> {
        point_edge_time_of_impact(p, dp, q, dq, r, dr)
    }

    #[test]
    fn a_fast_point_does_not_tunnel_through_a_static_edge() {
        // 100 units/s for 1/3000 s: 0.033 per step, through an edge 1e-3 below.
        let h = hit(
            DVec2::new(0.5, 0.001),
            DVec2::new(0.0, -100.0 / 3000.0),
            DVec2::new(0.0, 0.0),
            DVec2::ZERO,
            DVec2::new(1.0, 0.0),
            DVec2::ZERO,
        )
        .expect("a hit");
        assert!((h.time - 0.001 / (100.0 / 3000.0)).abs() < 1e-12);
        assert!((h.alpha - 0.5).abs() < 1e-12);
        assert_eq!(h.normal, DVec2::Y);
    }

    #[test]
    fn degenerate_motions_are_handled() {
        let (q, r) = (DVec2::ZERO, DVec2::X);
        // Against the unit edge along x, at rest.
        let at_rest = |p: DVec2, dp: DVec2| hit(p, dp, q, DVec2::ZERO, r, DVec2::ZERO);
        // No motion, not touching.
        assert!(at_rest(DVec2::new(0.5, 0.1), DVec2::ZERO).is_none());
        // Parallel motion beside the edge.
        assert!(at_rest(DVec2::new(0.5, 0.1), DVec2::X).is_none());
        // Point already on the edge and not moving: a hit at once.
        assert_eq!(
            at_rest(DVec2::new(0.3, 0.0), DVec2::ZERO).unwrap().time,
            0.0
        );
        // Sliding along the edge's line into its end.
        let slide = at_rest(DVec2::new(-0.5, 0.0), DVec2::new(1.0, 0.0)).unwrap();
        assert!((slide.time - 0.5).abs() < 1e-12 && slide.alpha == 0.0);
        // Passing exactly through an endpoint.
        let end = at_rest(DVec2::new(1.0, 0.5), DVec2::new(0.0, -1.0)).unwrap();
        assert!((end.time - 0.5).abs() < 1e-12 && end.alpha == 1.0);
        // Passing just beyond an endpoint.
        assert!(at_rest(DVec2::new(1.001, 0.5), DVec2::new(0.0, -1.0)).is_none());
        // Both moving together, never meeting.
        let d = DVec2::new(0.3, 0.2);
        assert!(hit(DVec2::new(0.5, 0.1), d, q, d, r, d).is_none());
        // A rotating edge sweeping over a resting point.
        let sweep = hit(
            DVec2::new(0.5, 0.3),
            DVec2::ZERO,
            q,
            DVec2::ZERO,
            r,
            DVec2::new(-0.2, 1.0),
        );
        assert!(sweep.is_some());
    }

    #[test]
    fn a_crossing_far_below_the_pair_size_is_found() {
        // The step of the 100 s spaghetti factory run at which two edges first crossed
        // (step 201 466): a point resting 3.5e-14 off an edge's line, moving with it
        // to 1e-14 per step. Every coefficient of the collinearity quadratic is then
        // of the order of the degenerate-case tolerance; dropping the quadratic term
        // moved the root from 0.93 (inside the step) to 1.06, and the crossing was
        // missed. The end orientation, computed as the crossing check computes it,
        // has the other sign than at the start.
        let p = DVec2::new(0.865400132384969, 0.08193518772812437);
        let dp = DVec2::new(6.40242010584905e-7, 2.0144803076899034e-7);
        let q = DVec2::new(0.9067516529516643, 0.07714971904176424);
        let dq = DVec2::new(5.597952890183997e-7, 2.1341995835763488e-7);
        let r = DVec2::new(0.8570831428427685, 0.08289768420882919);
        let dr = DVec2::new(5.594301372373597e-7, 2.1026472281696286e-7);
        let found = hit(p, dp, q, dq, r, dr).expect("the crossing is found");
        assert!(found.crosses, "{found:?}");
        assert!((found.time - 0.928).abs() < 1e-3, "{found:?}");
        assert!((found.alpha - 0.8326).abs() < 1e-3, "{found:?}");
        // The normal points to the side the point came from.
        assert!(found.normal.dot(p - q) > 0.0, "{found:?}");
        let end = |x: DVec2, d: DVec2| x + d;
        let side = |x: DVec2, a: DVec2, b: DVec2| (b - a).perp_dot(x - a);
        assert!(side(p, q, r) * side(end(p, dp), end(q, dq), end(r, dr)) < 0.0);

        // Synthetic cases at the same scale: a point 3.5e-14 or 1e-15 off the line,
        // moving across it with the edge carried along.
        let n = (r - q).perp().normalize();
        let common = DVec2::new(1.7e-3, 6.0e-4) / 3000.0;
        for (offset, drift) in [(3.5e-14, -7e-14), (-3.5e-14, 7e-14), (1e-15, -3e-15)] {
            let p = q + 0.8325 * (r - q) + offset * n;
            let found = hit(p, common + drift * n, q, common, r, common)
                .unwrap_or_else(|| panic!("offset {offset:e}, drift {drift:e}: missed"));
            assert!((found.alpha - 0.8325).abs() < 1e-6, "{found:?}");
            assert!(found.normal.dot(n) * offset > 0.0, "{found:?}");
        }
    }

    /// Brute force: sample the motion finely and report the first sample interval in
    /// which p crosses the edge's line while inside the edge.
    fn sampled_crossing(
        p: DVec2,
        dp: DVec2,
        q: DVec2,
        dq: DVec2,
        r: DVec2,
        dr: DVec2,
    ) -> Option<f64> {
        let samples = 4000;
        let side = |t: f64| {
            let (pt, qt, rt) = (p + t * dp, q + t * dq, r + t * dr);
            (
                (qt - pt).perp_dot(rt - pt),
                (pt - qt).dot(rt - qt) / (rt - qt).length_squared(),
            )
        };
        let mut previous = side(0.0);
        for i in 1..=samples {
            let t = i as f64 / samples as f64;
            let now = side(t);
            let inside = |alpha: f64| (0.0..=1.0).contains(&alpha);
            if previous.0.signum() != now.0.signum() && (inside(previous.1) || inside(now.1)) {
                // Confirm: the interpolated crossing lies on the edge.
                let s = previous.0 / (previous.0 - now.0);
                let tc = t - (1.0 - s) / samples as f64;
                let alpha = side(tc).1;
                if (0.001..=0.999).contains(&alpha) {
                    return Some(tc);
                }
            }
            previous = now;
        }
        None
    }

    #[test]
    fn pairs_whose_boxes_miss_have_no_contact() {
        // Points that pass just outside the edge's box, grazing its corners and
        // sides, or meet it: the boxes' test never turns away a pair the roots touch.
        let mut rng = StdRng::seed_from_u64(11);
        let v =
            |rng: &mut StdRng, s: f64| DVec2::new(rng.random_range(-s..s), rng.random_range(-s..s));
        let (mut missed, mut touching) = (0, 0);
        for case in 0..200_000 {
            let q = v(&mut rng, 1.0);
            let r = q + v(&mut rng, 0.6);
            let (dq, dr) = (v(&mut rng, 0.1), v(&mut rng, 0.1));
            // Start at an end of the edge or of its sweep, offset by a hair or by a lot.
            let corner = [q, r, q + dq, r + dr][case % 4];
            let offset = 10f64.powi(-((case % 13) as i32));
            let p = corner + v(&mut rng, offset);
            let dp = [DVec2::ZERO, v(&mut rng, offset), v(&mut rng, 1.0)][case % 3];
            let touches = time_of_impact(p, dp, q, dq, r, dr);
            if !boxes_meet(p, dp, q, dq, r, dr) {
                missed += 1;
                assert_eq!(touches, None, "case {case}");
            }
            touching += usize::from(touches.is_some());
        }
        assert!(missed > 10_000 && touching > 10_000, "{missed} {touching}");
    }

    #[test]
    fn roots_agree_with_brute_force_sampling() {
        let mut rng = StdRng::seed_from_u64(5);
        let mut crossings = 0;
        let v =
            |rng: &mut StdRng, s: f64| DVec2::new(rng.random_range(-s..s), rng.random_range(-s..s));
        for case in 0..20_000 {
            let p = v(&mut rng, 1.0);
            let q = v(&mut rng, 1.0);
            let r = q + v(&mut rng, 0.6);
            let scale = if case % 2 == 0 { 1.0 } else { 0.3 };
            let (dp, dq, dr) = (
                v(&mut rng, 2.0 * scale),
                v(&mut rng, scale),
                v(&mut rng, scale),
            );
            let found = hit(p, dp, q, dq, r, dr);
            if let Some(t) = sampled_crossing(p, dp, q, dq, r, dr) {
                crossings += 1;
                let found =
                    found.unwrap_or_else(|| panic!("case {case}: missed a crossing at {t}"));
                assert!(
                    found.time <= t + 1.0 / 4000.0,
                    "case {case}: hit at {} after crossing at {t}",
                    found.time
                );
            }
            if let Some(h) = found {
                // Every reported contact is real: p lies on the edge then.
                let (pt, qt, rt) = (p + h.time * dp, q + h.time * dq, r + h.time * dr);
                let (_, distance) = closest_on_segment(pt, qt, rt);
                assert!(
                    distance < 1e-9,
                    "case {case}: reported contact {distance} away"
                );
                assert!((h.normal.length() - 1.0).abs() < 1e-12);
            }
        }
        assert!(crossings > 500, "too few crossing cases: {crossings}");
    }
}
