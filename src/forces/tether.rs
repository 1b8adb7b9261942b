//! Tethers: a damped spring from a particle to a point, the force of a mouse drag.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::particle::SolverIndex;
use crate::state::ParticleState;

/// Pulls its particle towards `target` with `f = k (target − x) − c v`, every step.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct Tether {
    /// Where the particle is pulled.
    pub target: DVec2,
    /// Spring stiffness (N/m).
    pub stiffness: f64,
    /// Damping of the particle's velocity (N·s/m).
    pub damping: f64,
}

/// The tether force on a particle at `x` moving at `v`.
pub fn tether_force(tether: &Tether, x: DVec2, v: DVec2) -> DVec2 {
    tether.stiffness * (tether.target - x) - tether.damping * v
}

/// Add every tether's force (Forces stage, after the built-in forces).
pub fn apply_tethers(mut state: ResMut<ParticleState>, tethers: Query<(&Tether, &SolverIndex)>) {
    for (tether, index) in &tethers {
        if let Some(i) = index.get() {
            let f = tether_force(tether, state.position[i], state.velocity[i]);
            state.force[i] += f;
        }
    }
}
