//! Particle components: what a particle is, as data on an entity.
//!
//! State is `f64` throughout: the headline figure of this crate is a relative length
//! error near machine precision, which `f32` cannot represent.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::world::hooks::{on_particle_added, on_particle_removed, on_structure_changed};

/// Marks an entity as a simulated particle and brings in the components it needs.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy::math::DVec2;
/// # use bevy_strands::prelude::*;
/// # let mut world = World::new();
/// world.spawn((Particle, Position(DVec2::new(0.5, 0.5)), Mass(2.0)));
/// ```
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component)]
#[require(Position, Velocity, Mass, SolverIndex)]
#[component(on_add = on_particle_added, on_remove = on_particle_removed)]
pub struct Particle;

/// Position in world units (the canonical scenes use the unit box).
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Deref, DerefMut)]
#[reflect(Component)]
pub struct Position(pub DVec2);

/// Velocity in world units per second.
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Deref, DerefMut)]
#[reflect(Component)]
pub struct Velocity(pub DVec2);

/// Mass of a free particle. Must be finite and positive; a particle with a bad mass is
/// left out of the simulation with an error in
/// [`InputProblems`](crate::world::problems::InputProblems).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Deref, DerefMut)]
#[reflect(Component)]
pub struct Mass(pub f64);

impl Default for Mass {
    fn default() -> Self {
        Mass(1.0)
    }
}

/// A pinned particle is fixed: forces, constraints and collisions never move it, and
/// its velocity is zero whatever its [`Velocity`] says (the gather zeroes it). To drive
/// a particle along a path of your own, mark it [`Kinematic`] instead.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component)]
#[component(on_add = on_structure_changed, on_remove = on_structure_changed)]
pub struct Pinned;

/// A kinematic particle has infinite mass like a pinned one, but moves with its own
/// [`Velocity`]: the particle a user drives (a factory's inlet, a hand dragging a
/// rope's end). [`Pinned`] on the same particle wins.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component)]
#[component(on_add = on_structure_changed, on_remove = on_structure_changed)]
pub struct Kinematic;

/// A particle held where the finiteness guard froze it (a non-finite value appeared in
/// its island): simulated as pinned with zero velocity until the marker is removed.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component)]
#[component(on_add = on_structure_changed, on_remove = on_structure_changed)]
pub struct Frozen;

/// A particle at rest in a sleeping strand: held like a pinned one, with zero velocity,
/// its position kept exactly, and no cost to a step beyond being collided against. The
/// sleeping system (the `sleeping` module) adds it to every particle of a strand that
/// has stayed within [`SleepConfig::drift`](crate::world::config::SleepConfig) of one
/// place for its `time`, as have the awake strands it touches, and removes it when
/// something moving comes within reach, when a particle of the strand is written to,
/// when one of its anchors moves, or when what it rests on is despawned. Removing it
/// yourself wakes the particle's strand.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component)]
#[component(on_add = on_structure_changed, on_remove = on_structure_changed)]
pub struct Sleeping;

/// A constant force applied to the particle each step, on top of gravity.
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Deref, DerefMut)]
#[reflect(Component)]
pub struct ExternalForce(pub DVec2);

/// Index of the particle in the packed solver arrays, maintained by the topology
/// rebuild. `SolverIndex::NONE` means "not simulated" (not yet seen, or rejected).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
#[reflect(Component)]
pub struct SolverIndex(pub u32);

impl SolverIndex {
    /// Not part of the packed state.
    pub const NONE: SolverIndex = SolverIndex(u32::MAX);

    /// The packed index, if the particle is simulated.
    pub fn get(self) -> Option<usize> {
        (self != Self::NONE).then_some(self.0 as usize)
    }
}

impl Default for SolverIndex {
    fn default() -> Self {
        Self::NONE
    }
}

/// Pulls its particle towards `target` with `f = k (target − x) − c v`, every step: the
/// force of a mouse drag or a game's grab.
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
