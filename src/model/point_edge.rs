//! A point against an edge: the three particles of a contact and its weights.
//!
//! The contact point on edge (q, r) is `(1 − α) q + α r`, so the relative velocity of
//! point p against it is `Σ cᵢ vᵢ` with coefficients `c = (1, α − 1, −α)`. A change `Δ`
//! of that relative velocity is produced by the impulse `J = Δ / Σ cᵢ² wᵢ` applied as
//! `cᵢ wᵢ J` to each particle: the three impulses sum to zero, so linear momentum is
//! conserved. Pinned particles have weight 0. Collision impulses and the contact rows of
//! the constraint solve both take their coefficients from here.

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
    /// The particles, in the order of [`PointEdgePair::coefficients`].
    pub fn particles(&self) -> [usize; 3] {
        [self.p, self.q, self.r]
    }

    /// `(1, α − 1, −α)`: the relative velocity is `Σ cᵢ vᵢ`.
    pub fn coefficients(&self) -> [f64; 3] {
        [1.0, self.alpha - 1.0, -self.alpha]
    }

    /// Relative velocity of the point with respect to the edge's contact point.
    pub fn relative_velocity(&self, velocity: &[DVec2]) -> DVec2 {
        velocity[self.p] - velocity[self.q].lerp(velocity[self.r], self.alpha)
    }

    /// `Σ cᵢ² wᵢ = w_p + (1 − α)² w_q + α² w_r`: the inverse of the pair's effective mass.
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
        // The coefficients give the same relative velocity and weight.
        let c = pair.coefficients();
        let by_coefficients: DVec2 = (0..3).map(|i| c[i] * velocity[i]).sum();
        assert!((by_coefficients - pair.relative_velocity(&velocity)).length() < 1e-14);
        let weight: f64 = (0..3).map(|i| c[i] * c[i] * inverse_mass[i]).sum();
        assert!((weight - pair.weight(&inverse_mass)).abs() < 1e-15);
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
}
