//! The Forces stage: every force on every particle, accumulated into
//! [`ParticleState::force`]. Each force element is a pure kernel on slices in its own
//! module; [`accumulate_forces`] is the thin system that runs them in a fixed order.
//!
//! User forces go in [`StepSet::Forces`](crate::schedule::StepSet::Forces) after
//! [`accumulate_forces`] (and [`tether::apply_tethers`], the mouse drag's spring), adding
//! to the accumulator.

pub mod bending;
pub mod damping;
pub mod gravity;
pub mod springs;
pub mod tether;

use bevy::prelude::*;

use crate::config::StrandsConfig;
use crate::state::ParticleState;
use crate::topology::Topology;

/// Clear the accumulators to the external forces, then add gravity, mass-proportional
/// damping, stretch springs and bending.
pub fn accumulate_forces(
    config: Res<StrandsConfig>,
    topology: Res<Topology>,
    mut state: ResMut<ParticleState>,
) {
    let ParticleState {
        position,
        velocity,
        force,
        external_force,
        mass,
        ..
    } = &mut *state;
    force.copy_from_slice(external_force);
    gravity::add_gravity(mass, force, config.gravity);
    damping::add_mass_damping(mass, velocity, force, config.damping);
    springs::add_stretch_springs(&topology.edges, position, velocity, force);
    bending::add_bending(&topology.bends, position, velocity, force);
}
