//! Collision impulses between a point and an edge.
//!
//! A change `Δ` of the relative velocity `v_p − ((1 − α) v_q + α v_r)` is produced by
//! the impulse `J = Δ / (w_p + (1 − α)² w_q + α² w_r)` on p and `−(1 − α) J`, `−α J`
//! on q and r: the relative velocity changes by exactly Δ and, since the three
//! impulses sum to zero, linear momentum is conserved. Pinned particles have weight 0.

use bevy::math::DVec2;

/// The three particles of a point–edge pair and the contact's coordinate on the edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointEdgePair {
    /// The point.
    pub p: usize,
    /// The edge's first particle.
    pub q: usize,
    /// The edge's second particle.
    pub r: usize,
    /// Contact point `(1 − α) q + α r`.
    pub alpha: f64,
}

impl PointEdgePair {
    /// Relative velocity of the point with respect to the edge's contact point.
    pub fn relative_velocity(&self, velocity: &[DVec2]) -> DVec2 {
        velocity[self.p] - velocity[self.q].lerp(velocity[self.r], self.alpha)
    }

    /// `w_p + (1 − α)² w_q + α² w_r`: the inverse of the pair's effective mass.
    pub fn weight(&self, inverse_mass: &[f64]) -> f64 {
        let a = self.alpha;
        inverse_mass[self.p]
            + (1.0 - a) * (1.0 - a) * inverse_mass[self.q]
            + a * a * inverse_mass[self.r]
    }

    /// Change the relative velocity by `delta`, conserving momentum. Returns false
    /// (and changes nothing) when all three particles are pinned.
    pub fn apply(&self, delta: DVec2, velocity: &mut [DVec2], inverse_mass: &[f64]) -> bool {
        let weight = self.weight(inverse_mass);
        if weight <= 0.0 {
            return false;
        }
        let impulse = delta / weight;
        velocity[self.p] += inverse_mass[self.p] * impulse;
        velocity[self.q] -= (1.0 - self.alpha) * inverse_mass[self.q] * impulse;
        velocity[self.r] -= self.alpha * inverse_mass[self.r] * impulse;
        true
    }
}

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

/// Normal velocity change for a collision found by continuous detection: stop the
/// approach and bounce with restitution `e`.
pub fn collision_normal_change(normal_velocity: f64, restitution: f64) -> f64 {
    if normal_velocity < 0.0 {
        -(1.0 + restitution) * normal_velocity
    } else {
        0.0
    }
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
    fn impulses_change_the_relative_velocity_exactly_and_conserve_momentum() {
        let pair = PointEdgePair {
            p: 0,
            q: 1,
            r: 2,
            alpha: 0.3,
        };
        let inverse_mass = [0.5, 2.0, 1.0 / 3.0];
        let mut velocity = [
            DVec2::new(1.0, -2.0),
            DVec2::new(0.1, 0.2),
            DVec2::new(-0.3, 0.4),
        ];
        let momentum = |v: &[DVec2]| -> DVec2 { (0..3).map(|i| v[i] / inverse_mass[i]).sum() };
        let before = momentum(&velocity);
        let relative = pair.relative_velocity(&velocity);
        let delta = DVec2::new(0.25, 1.5);
        assert!(pair.apply(delta, &mut velocity, &inverse_mass));
        assert!((pair.relative_velocity(&velocity) - relative - delta).length() < 1e-14);
        assert!((momentum(&velocity) - before).length() < 1e-14);
    }

    #[test]
    fn pinned_edges_take_no_impulse() {
        let pair = PointEdgePair {
            p: 0,
            q: 1,
            r: 2,
            alpha: 0.5,
        };
        let inverse_mass = [1.0, 0.0, 0.0];
        let mut velocity = [DVec2::new(0.0, -1.0), DVec2::ZERO, DVec2::ZERO];
        pair.apply(DVec2::new(0.0, 1.0), &mut velocity, &inverse_mass);
        assert_eq!(velocity, [DVec2::ZERO, DVec2::ZERO, DVec2::ZERO]);
        let all_pinned = [0.0; 3];
        assert!(!pair.apply(DVec2::Y, &mut velocity, &all_pinned));
    }

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
