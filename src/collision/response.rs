//! The velocity changes of a point–edge contact: how much the relative velocity must
//! change along the normal (a collision's, or a proximity cushion's), and Coulomb
//! friction on the tangential part. [`PointEdgePair::apply`](crate::model::PointEdgePair::apply)
//! turns a change into momentum-conserving impulses.

use bevy::math::DVec2;

/// The relative-velocity change of a contact along unit normal `n`: a normal change
/// `normal_change` (≥ 0, pushing apart) and Coulomb friction removing up to
/// `friction × normal_change` of the tangential relative velocity.
pub fn contact_change(relative: DVec2, n: DVec2, normal_change: f64, friction: f64) -> DVec2 {
    let tangential = relative - relative.dot(n) * n;
    let speed = tangential.length();
    let slowdown = if speed > 0.0 {
        (friction * normal_change).min(speed) / speed
    } else {
        0.0
    };
    normal_change * n - slowdown * tangential
}

/// Normal velocity change for a collision: relative normal velocity `vn`, gap along
/// the normal at the start of the step `g0`. The pair leaves with at least the bounce
/// of restitution `e`, and at least the velocity that ends the step `separation` apart
/// (`g0 + dt vn' ≥ separation`): a pair that started apart may close in to the
/// separation, one that started closer is pushed out to it. A contact is therefore
/// never left touching, where rounding alone would decide its side. A gap below zero
/// along the normal of the moment of contact (an edge that turned during the step) is
/// taken as touching: the push out is never more than the separation.
pub fn collision_normal_change(vn: f64, g0: f64, separation: f64, e: f64, dt: f64) -> f64 {
    let bounce = if vn < 0.0 { -e * vn } else { vn };
    let target = bounce.max((separation - g0.max(0.0)) / dt);
    (target - vn).max(0.0)
}

/// Normal velocity change for a pair that would end the step closer than thickness
/// `h`: start separation `d0`, relative normal velocity `vn`, step `dt`. From outside
/// the cushion, just enough to end the step at distance `h`; from inside, enough to
/// push out by a tenth of the overlap per step, so resting contact settles without
/// popping. A target, not an increment: applying it twice changes nothing.
pub fn repulsion_normal_change(d0: f64, vn: f64, h: f64, dt: f64) -> f64 {
    let target = if d0 >= h {
        (h - d0) / dt
    } else {
        0.1 * (h - d0) / dt
    };
    (target - vn).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friction_is_coulomb() {
        let n = DVec2::Y;
        // Sticks when the tangential speed is below μ × the normal change...
        let stick = contact_change(DVec2::new(0.1, -1.0), n, 1.0, 0.3);
        assert_eq!(stick, DVec2::new(-0.1, 1.0));
        // ...and slides, slowed by μ × the normal change, when above.
        let slide = contact_change(DVec2::new(2.0, -1.0), n, 1.0, 0.3);
        assert!((slide - DVec2::new(-0.3, 1.0)).length() < 1e-15);
    }

    #[test]
    fn a_collision_leaves_the_pair_the_separation_apart() {
        let (dt, separation) = (1.0 / 3000.0, 4e-4);
        // Started well apart, approaching: stopped (inelastic), the gap kept.
        let change = collision_normal_change(-2.0, 0.003, separation, 0.0, dt);
        assert_eq!(change, 2.0);
        // Started touching, creeping in: pushed out to end at the separation.
        let (vn, g0) = (-1e-10, 1e-14);
        let change = collision_normal_change(vn, g0, separation, 0.0, dt);
        assert!((g0 + dt * (vn + change) - separation).abs() < 1e-15);
        // Restitution bounces back when that is more.
        let change = collision_normal_change(-2.0, 0.003, separation, 0.5, dt);
        assert_eq!(change, 3.0);
        // Already leaving fast enough: nothing.
        assert_eq!(collision_normal_change(5.0, 0.0, separation, 0.0, dt), 0.0);
    }

    #[test]
    fn repulsion_stops_at_the_thickness_and_pushes_out_gently() {
        let (h, dt) = (0.004, 1.0 / 3000.0);
        // Approaching from outside: end the step exactly at h.
        let vn = -3.0;
        let dv = repulsion_normal_change(0.005, vn, h, dt);
        assert!((0.005 + dt * (vn + dv) - h).abs() < 1e-15);
        // Already far: nothing.
        assert_eq!(repulsion_normal_change(0.01, -1.0, h, dt), 0.0);
        // Deep inside and at rest: a tenth of the overlap per step.
        let dv = repulsion_normal_change(0.002, 0.0, h, dt);
        assert!((dv * dt - 0.0002).abs() < 1e-15);
        // Idempotent: once applied, nothing more.
        assert_eq!(repulsion_normal_change(0.002, dv, h, dt), 0.0);
        // Already separating fast enough: nothing.
        assert_eq!(repulsion_normal_change(0.002, 5.0, h, dt), 0.0);
    }
}
