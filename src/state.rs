//! The packed particle state the step stages run on (DESIGN §3).
//!
//! Authoritative state lives on the particle entities. At the start of each tick it is
//! gathered into these arrays, in the order the topology rebuild chose (strand by
//! strand, so each path island is contiguous); the stages of every step read and
//! write only the arrays; at the end of the tick positions and velocities are written
//! back. Gather and write-back walk the particle query linearly through
//! [`SolverIndex`], so no entity look-up happens per particle per stage.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::particle::{ExternalForce, Mass, Particle, Pinned, Position, SolverIndex, Velocity};
use crate::topology::{InputProblems, Topology};

/// Structure-of-arrays particle state, indexed by [`SolverIndex`].
#[derive(Resource, Default, Debug, Clone)]
pub struct ParticleState {
    /// The entity of each packed particle.
    pub entity: Vec<Entity>,
    /// Position at the start of the current step (the end of the previous one).
    pub position: Vec<DVec2>,
    /// Velocity; after the predictor, the candidate velocity of this step.
    pub velocity: Vec<DVec2>,
    /// Force accumulator of the current step.
    pub force: Vec<DVec2>,
    /// Constant external force per particle.
    pub external_force: Vec<DVec2>,
    /// Mass (the pinned particles' too, for kinetic figures).
    pub mass: Vec<f64>,
    /// Inverse mass, 0 for pinned particles.
    pub inverse_mass: Vec<f64>,
    /// Whether the particle took part in a contact this step.
    pub in_contact: Vec<bool>,
}

impl ParticleState {
    /// Number of packed particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether no particle is packed.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Whether particle `i` is pinned (infinite mass).
    pub fn is_pinned(&self, i: usize) -> bool {
        self.inverse_mass[i] == 0.0
    }

    /// Total linear momentum of the free particles.
    pub fn linear_momentum(&self) -> DVec2 {
        (0..self.len())
            .filter(|&i| !self.is_pinned(i))
            .map(|i| self.mass[i] * self.velocity[i])
            .sum()
    }

    /// Total angular momentum of the free particles about `origin`.
    pub fn angular_momentum(&self, origin: DVec2) -> f64 {
        (0..self.len())
            .filter(|&i| !self.is_pinned(i))
            .map(|i| self.mass[i] * (self.position[i] - origin).perp_dot(self.velocity[i]))
            .sum()
    }

    /// Kinetic energy of the free particles.
    pub fn kinetic_energy(&self) -> f64 {
        (0..self.len())
            .filter(|&i| !self.is_pinned(i))
            .map(|i| 0.5 * self.mass[i] * self.velocity[i].length_squared())
            .sum()
    }

    pub(crate) fn resize(&mut self, entities: Vec<Entity>) {
        let n = entities.len();
        self.entity = entities;
        self.position.resize(n, DVec2::ZERO);
        self.velocity.resize(n, DVec2::ZERO);
        self.force.resize(n, DVec2::ZERO);
        self.external_force.resize(n, DVec2::ZERO);
        self.mass.resize(n, 1.0);
        self.inverse_mass.resize(n, 1.0);
        self.in_contact.resize(n, false);
    }
}

/// Why a particle's data cannot be simulated, if it cannot.
pub(crate) fn particle_problem(
    position: DVec2,
    velocity: DVec2,
    mass: f64,
    pinned: bool,
) -> Option<String> {
    if !position.is_finite() {
        Some(format!("position {position:?} is not finite"))
    } else if !velocity.is_finite() {
        Some(format!("velocity {velocity:?} is not finite"))
    } else if !(pinned || mass.is_finite() && mass > 0.0) {
        Some(format!("mass {mass} must be positive and finite"))
    } else {
        None
    }
}

type GatherQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static SolverIndex,
        &'static Position,
        &'static Velocity,
        &'static Mass,
        Has<Pinned>,
        Option<&'static ExternalForce>,
    ),
    With<Particle>,
>;

/// Copy the entities' state into the packed arrays (start of a tick).
pub fn gather(
    mut state: ResMut<ParticleState>,
    mut topology: ResMut<Topology>,
    mut problems: ResMut<InputProblems>,
    particles: GatherQuery,
) {
    for (entity, index, position, velocity, mass, pinned, external) in &particles {
        let Some(i) = index.get() else { continue };
        if let Some(problem) = particle_problem(position.0, velocity.0, mass.0, pinned) {
            // Keep the last good packed state; the next rebuild leaves the particle out.
            problems.report(entity, problem);
            topology.mark_changed();
            continue;
        }
        state.position[i] = position.0;
        state.velocity[i] = velocity.0;
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
