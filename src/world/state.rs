//! The packed particle state the step stages run on.
//!
//! Authoritative state lives on the particle entities. At the start of each tick it is
//! gathered into these arrays, in the order the topology rebuild chose (strand by
//! strand, so each path island is contiguous); the stages of every step read and
//! write only the arrays; at the end of the tick positions and velocities are written
//! back (the `sync` module's systems).

use bevy::math::DVec2;
use bevy::prelude::*;

/// Structure-of-arrays particle state, indexed by each particle's `SolverIndex`.
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
    /// Inverse mass, 0 for pinned particles (the topology's `pinned` is the record of
    /// which those are; this is derived from it at every gather).
    pub inverse_mass: Vec<f64>,
    /// Whether the particle took part in a contact this step.
    pub in_contact: Vec<bool>,
    /// What the velocity changes by once Integrate has moved the particle: where the
    /// projection re-stepped its island in substeps, the last substep's velocity less
    /// the step's chord (the motion the rest of the step sees); otherwise zero.
    pub end_velocity_change: Vec<DVec2>,
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

    /// Become a copy of `other`, reusing this one's buffers (no allocation once they
    /// are as long).
    pub fn copy_from(&mut self, other: &ParticleState) {
        copy_buffer(&mut self.entity, &other.entity);
        copy_buffer(&mut self.external_force, &other.external_force);
        copy_buffer(&mut self.mass, &other.mass);
        copy_buffer(&mut self.inverse_mass, &other.inverse_mass);
        self.copy_step_from(other);
    }

    /// Copy from `other` only the arrays a step writes (positions, velocities, forces,
    /// contact flags, end-of-step velocity changes): what step halving saves and puts
    /// back. Entities, masses and external forces are set by the tick's gather and only
    /// read by its steps, so a step's save need not move them (two fifths of the bytes).
    pub fn copy_step_from(&mut self, other: &ParticleState) {
        copy_buffer(&mut self.position, &other.position);
        copy_buffer(&mut self.velocity, &other.velocity);
        copy_buffer(&mut self.force, &other.force);
        copy_buffer(&mut self.in_contact, &other.in_contact);
        self.end_velocity_change
            .clone_from(&other.end_velocity_change);
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
        self.end_velocity_change.resize(n, DVec2::ZERO);
    }
}

/// Make `copy` hold what `source` holds, keeping at least `source`'s capacity so that a
/// copy taken every step grows as seldom as its source does.
pub fn copy_buffer<T: Clone>(copy: &mut Vec<T>, source: &Vec<T>) {
    copy.clear();
    if copy.capacity() < source.len() {
        copy.reserve(source.capacity());
    }
    copy.extend_from_slice(source);
}
