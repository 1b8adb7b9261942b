//! Copying between the entities and the packed state: [`gather`] at the start of a
//! tick, [`write_back`] at its end. Both walk the particle query linearly through
//! [`SolverIndex`], so no entity look-up happens per particle.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::model::validate::check_particle;
use crate::world::hooks::TopologyDirty;
use crate::world::particle::{
    ExternalForce, Frozen, Mass, Particle, Pinned, Position, Sleeping, SolverIndex, Velocity,
};
use crate::world::problems::InputProblems;
use crate::world::state::ParticleState;
use crate::world::topology::Topology;

type GatherQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static SolverIndex,
        &'static Position,
        &'static Velocity,
        &'static Mass,
        Option<&'static ExternalForce>,
        Has<Pinned>,
        Has<Frozen>,
        Has<Sleeping>,
    ),
    With<Particle>,
>;

/// Copy the entities' state into the packed arrays (start of a tick).
pub fn gather(
    mut state: ResMut<ParticleState>,
    topology: Res<Topology>,
    mut dirty: ResMut<TopologyDirty>,
    mut problems: ResMut<InputProblems>,
    particles: GatherQuery,
) {
    for (entity, index, position, velocity, mass, external, fixed, frozen, asleep) in &particles {
        let Some(i) = index.get() else { continue };
        let pinned = topology.pinned[i];
        if let Err(problem) = check_particle(position.0, velocity.0, mass.0, pinned) {
            // Keep the last good packed state; the next rebuild leaves the particle out.
            problems.report(entity, problem.to_string());
            dirty.mark();
            continue;
        }
        state.position[i] = position.0;
        // A pinned, frozen or sleeping particle stays where it is, whatever its
        // velocity says.
        state.velocity[i] = if fixed || frozen || asleep {
            DVec2::ZERO
        } else {
            velocity.0
        };
        state.mass[i] = mass.0;
        state.inverse_mass[i] = if pinned { 0.0 } else { 1.0 / mass.0 };
        state.external_force[i] = match external {
            Some(force) if !force.is_finite() => {
                problems.report(
                    entity,
                    format!("external force {:?} is not finite", force.0),
                );
                DVec2::ZERO
            }
            Some(force) => force.0,
            None => DVec2::ZERO,
        };
    }
}

/// Copy positions and velocities back to the entities (end of a tick).
pub fn write_back(
    state: Res<ParticleState>,
    mut particles: Query<(&SolverIndex, &mut Position, &mut Velocity)>,
) {
    for (index, mut position, mut velocity) in &mut particles {
        let Some(i) = index.get() else { continue };
        position.set_if_neq(Position(state.position[i]));
        velocity.set_if_neq(Velocity(state.velocity[i]));
    }
}
