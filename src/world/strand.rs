//! Strands as components: ordered chains of particles whose edges keep their rest
//! length.
//!
//! A strand is an entity with a [`Strand`] component listing its particles in order.
//! The particles it created are owned through the [`StrandOf`] relationship, so
//! despawning a strand despawns them. A strand may also list particles owned by
//! another strand (a hair branching off a trunk, a rope tied to a ring): that is how
//! trees and graphs are built, and why connectivity is kept apart from ownership.

use bevy::prelude::*;

use crate::model::validate::{NumberError, non_negative};
use crate::model::{bend_count, edge_count};
use crate::world::hooks::{on_strand_inserted, on_strand_removed};

/// The connectivity of a strand: its particles in order, the rest length of each edge,
/// the rest turning angle at each bending vertex, and whether the last particle joins
/// the first.
///
/// Edge `k` joins `particles[k]` and `particles[k + 1]`; a closed strand has one more
/// edge, from the last particle back to the first. Bending vertex `k` of an open strand
/// is `particles[k + 1]`; of a closed strand, `particles[k]`.
#[derive(Component, Reflect, Clone, Debug, Default, PartialEq)]
#[reflect(Component)]
#[component(on_insert = on_strand_inserted, on_remove = on_strand_removed)]
pub struct Strand {
    /// Particles in order along the strand.
    pub particles: Vec<Entity>,
    /// Rest length of each edge.
    pub rest_lengths: Vec<f64>,
    /// Rest turning angle (radians, counter-clockwise positive) at each bending vertex.
    /// Empty means straight at rest.
    pub rest_angles: Vec<f64>,
    /// Whether the strand is a loop.
    pub closed: bool,
}

impl Strand {
    /// Number of edges the particle list implies.
    pub fn edge_count(&self) -> usize {
        edge_count(self.particles.len(), self.closed)
    }

    /// Number of bending vertices the particle list implies.
    pub fn bend_count(&self) -> usize {
        bend_count(self.particles.len(), self.closed)
    }

    /// The particle pair `(a, b)` of edge `k`.
    pub fn edge(&self, k: usize) -> (Entity, Entity) {
        let n = self.particles.len();
        (self.particles[k], self.particles[(k + 1) % n])
    }

    /// Whether an edge of this strand joins `a` and `b` (in either order).
    pub fn joins(&self, a: Entity, b: Entity) -> bool {
        (0..self.edge_count()).any(|k| {
            let (p, q) = self.edge(k);
            (p, q) == (a, b) || (p, q) == (b, a)
        })
    }
}

/// Marks a particle as owned by a strand: it is despawned with the strand.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = StrandParticles)]
pub struct StrandOf(pub Entity);

/// The particles a strand owns (the targets of [`StrandOf`]), in spawn order.
#[derive(Component, Debug, Default)]
#[relationship_target(relationship = StrandOf, linked_spawn)]
pub struct StrandParticles(Vec<Entity>);

impl StrandParticles {
    /// The owned particles.
    pub fn entities(&self) -> &[Entity] {
        &self.0
    }
}

/// Elastic material of a strand's force elements. Strands without this component use
/// the default material of the step configuration (`StrandsConfig::material`).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
#[reflect(Component)]
pub struct StrandMaterial {
    /// Stretch spring stiffness as force per unit strain (N): `f = k (ℓ/L − 1)`.
    /// Used by the springs solver and, when enabled, on top of constraints.
    pub stretch_stiffness: f64,
    /// Damping of the stretch spring along the edge (N·s/m).
    pub stretch_damping: f64,
    /// Bending stiffness (N·m²): energy `k_b/ℓ̄ (θ − θ̄)²` per bending vertex.
    pub bending_stiffness: f64,
    /// Damping of the turning-angle rate (N·m·s).
    pub bending_damping: f64,
}

impl Default for StrandMaterial {
    fn default() -> Self {
        Self {
            stretch_stiffness: 1.0e4,
            stretch_damping: 5.0,
            bending_stiffness: 1.0e-3,
            bending_damping: 1.0e-5,
        }
    }
}

impl StrandMaterial {
    /// No springs and no bending: the material of static walls.
    pub const INERT: StrandMaterial = StrandMaterial {
        stretch_stiffness: 0.0,
        stretch_damping: 0.0,
        bending_stiffness: 0.0,
        bending_damping: 0.0,
    };

    /// This material in a world of `unit` world units per metre, masses unchanged:
    /// forces scale with the unit, so the stretch stiffness (a force) by `unit`, the
    /// bending stiffness (force × length²) by `unit³` and its damping by `unit²`; the
    /// stretch damping (force per speed) is the same.
    pub fn with_length_unit(self, unit: f64) -> Self {
        Self {
            stretch_stiffness: self.stretch_stiffness * unit,
            stretch_damping: self.stretch_damping,
            bending_stiffness: self.bending_stiffness * unit.powi(3),
            bending_damping: self.bending_damping * unit.powi(2),
        }
    }

    /// Every coefficient must be finite and not negative.
    pub fn validate(&self) -> Result<(), NumberError> {
        non_negative("stretch_stiffness", self.stretch_stiffness)?;
        non_negative("stretch_damping", self.stretch_damping)?;
        non_negative("bending_stiffness", self.bending_stiffness)?;
        non_negative("bending_damping", self.bending_damping)
    }
}

/// What a strand represents; picks its colour in pictures and groups it in reports.
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[reflect(Component)]
pub enum StrandKind {
    /// A generic rope or strand.
    #[default]
    Rope,
    /// A strand from the spaghetti factory.
    Spaghetti,
    /// A meatball: a small closed loop.
    Meatball,
    /// Static container walls.
    Wall,
    /// A hair of a furry creature.
    Hair,
}

impl StrandKind {
    /// The kind's colour (sRGB) in every picture: windows and exported frames alike.
    pub fn color(self) -> [u8; 3] {
        match self {
            StrandKind::Spaghetti => [240, 200, 70],
            StrandKind::Meatball => [150, 85, 40],
            StrandKind::Wall => [140, 140, 140],
            StrandKind::Hair => [225, 160, 110],
            StrandKind::Rope => [110, 170, 235],
        }
    }
}
