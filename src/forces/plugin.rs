//! The Forces stage's systems: the built-in forces, then the tethers.

use bevy::prelude::*;

use super::{bending, damping, gravity, springs, tether};
use crate::schedule::{StepSet, StrandsStep};
use crate::world::config::{BendingModel, StrandsConfig};
use crate::world::particle::{SolverIndex, Tether};
use crate::world::state::ParticleState;
use crate::world::topology::Topology;

/// Accumulates every force of a step.
pub struct ForcesPlugin;

impl Plugin for ForcesPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            StrandsStep,
            (accumulate_forces, apply_tethers)
                .chain()
                .in_set(StepSet::Forces),
        );
    }
}

/// Clear the accumulators to the external forces, then add gravity, mass-proportional
/// damping, stretch springs and (with the angle model) bending.
pub fn accumulate_forces(
    config: Res<StrandsConfig>,
    topology: Res<Topology>,
    mut state: ResMut<ParticleState>,
    mut shares: Local<(Option<(u64, usize)>, bending::BendingShares)>,
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
    // The quadratic model is integrated implicitly, in the Predict stage; the angle
    // model's stiff strands are corrected there.
    if config.bending != BendingModel::Quadratic {
        // The shares depend only on the topology and the thread count.
        let key = Some((topology.version, config.worker_threads()));
        let (cut_for, shares) = &mut *shares;
        if *cut_for != key {
            shares.cut(&topology.bends, force.len(), config.worker_threads());
            *cut_for = key;
        }
        bending::add_bending_shared(&topology.bends, position, velocity, force, shares);
    }
}

/// Add every tether's force (after the built-in forces).
pub fn apply_tethers(mut state: ResMut<ParticleState>, tethers: Query<(&Tether, &SolverIndex)>) {
    for (t, index) in &tethers {
        if let Some(i) = index.get() {
            let f = tether::tether_force(
                t.target,
                t.stiffness,
                t.damping,
                state.position[i],
                state.velocity[i],
            );
            state.force[i] += f;
        }
    }
}
