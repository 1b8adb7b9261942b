//! Contact rows: the inequalities `Σ cᵢ n·vᵢ ≥ target` a contact projection must
//! respect, with friction along their tangent, and the impulses they carry.

use bevy::math::DVec2;

use crate::model::PointEdgePair;

/// A contact that a contact projection must not make approach: `Σ cᵢ n·vᵢ ≥ target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactRow {
    /// The particles involved (packed indices).
    pub particles: [u32; 3],
    /// Their coefficients.
    pub coefficients: [f64; 3],
    /// The contact normal.
    pub normal: DVec2,
    /// The smallest allowed `Σ cᵢ n·vᵢ`.
    pub target: f64,
    /// Coulomb friction coefficient of the row's tangential part (a contact projection
    /// stops sliding along `normal.perp()` with at most this times the normal impulse).
    pub friction: f64,
}

/// The total impulse a contact row applied (momentum): along its normal (never
/// negative) and along its tangent (within the friction cone).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RowImpulse {
    /// Along the normal, pushing apart.
    pub normal: f64,
    /// Along the tangent `normal.perp()`.
    pub tangent: f64,
}

impl ContactRow {
    /// A point–edge pair along `normal`, with the current relative normal velocity as
    /// the target.
    pub fn point_edge(pair: PointEdgePair, normal: DVec2, velocity: &[DVec2]) -> ContactRow {
        let mut row = ContactRow {
            particles: pair.particles().map(|i| i as u32),
            coefficients: pair.coefficients(),
            normal,
            target: 0.0,
            friction: 0.0,
        };
        row.target = row.normal_velocity(velocity);
        row
    }

    /// `Σ cᵢ n·vᵢ` for these velocities.
    pub fn normal_velocity(&self, velocity: &[DVec2]) -> f64 {
        self.particles
            .iter()
            .zip(self.coefficients)
            .map(|(&p, c)| c * self.normal.dot(velocity[p as usize]))
            .sum()
    }
}
