//! Strands: ordered chains of particles whose edges keep their rest length.
//!
//! A strand is an entity with a [`Strand`] component listing its particles in order.
//! The particles it created are owned through the [`StrandOf`] relationship, so
//! despawning a strand despawns them. A strand may also list particles owned by
//! another strand (a hair branching off a trunk, a rope tied to a ring): that is how
//! trees and graphs are built, and why connectivity is kept apart from ownership.

use bevy::ecs::lifecycle::HookContext;
use bevy::ecs::world::DeferredWorld;
use bevy::math::DVec2;
use bevy::prelude::*;
use thiserror::Error;

use crate::particle::{Mass, Particle, Pinned, Position, Velocity};
use crate::topology::mark_topology_changed;

/// The connectivity of a strand: its particles in order, the rest length of each edge,
/// the rest turning angle at each bending vertex, and whether the last particle joins
/// the first.
///
/// Edge `k` joins `particles[k]` and `particles[k + 1]`; a closed strand has one more
/// edge, from the last particle back to the first. Bending vertex `k` of an open strand
/// is `particles[k + 1]`; of a closed strand, `particles[k]`.
#[derive(Component, Reflect, Clone, Debug, Default, PartialEq)]
#[reflect(Component)]
#[component(on_insert = on_strand_changed, on_remove = on_strand_changed)]
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
}

pub(crate) fn edge_count(particles: usize, closed: bool) -> usize {
    match (particles, closed) {
        (0, _) => 0,
        (n, false) => n - 1,
        (n, true) => n,
    }
}

pub(crate) fn bend_count(particles: usize, closed: bool) -> usize {
    if closed {
        particles
    } else {
        particles.saturating_sub(2)
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
/// [`StrandsConfig::material`](crate::config::StrandsConfig::material).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
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

/// What a strand represents; picks its colour in pictures and groups it in reports.
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
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

fn on_strand_changed(world: DeferredWorld, _: HookContext) {
    mark_topology_changed(world);
}

/// Why a strand description cannot be built.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StrandError {
    /// Too few particles for the strand's kind.
    #[error("a {kind} strand needs at least {min} particles, got {got}")]
    TooFewParticles {
        /// "open" or "closed".
        kind: &'static str,
        /// The minimum.
        min: usize,
        /// What was given.
        got: usize,
    },
    /// A coordinate or velocity is NaN or infinite.
    #[error("{what} of particle {index} is not finite: {value:?}")]
    NotFinite {
        /// Which quantity.
        what: &'static str,
        /// Particle index.
        index: usize,
        /// The bad value.
        value: DVec2,
    },
    /// Two consecutive particles coincide, which would make a zero-length edge.
    #[error("particles {a} and {b} coincide at {at:?}: an edge needs a positive length")]
    CoincidentParticles {
        /// First particle index.
        a: usize,
        /// Second particle index.
        b: usize,
        /// Where.
        at: DVec2,
    },
    /// A rest length is zero, negative or not finite.
    #[error("rest length of edge {edge} must be positive and finite, got {value}")]
    BadRestLength {
        /// Edge index.
        edge: usize,
        /// The bad value.
        value: f64,
    },
    /// A list has the wrong length.
    #[error("{what} has {got} entries, expected {expected}")]
    WrongLength {
        /// Which list.
        what: &'static str,
        /// What was given.
        got: usize,
        /// What the particle count implies.
        expected: usize,
    },
    /// A mass is zero, negative or not finite.
    #[error("mass of particle {index} must be positive and finite, got {value}")]
    BadMass {
        /// Particle index.
        index: usize,
        /// The bad value.
        value: f64,
    },
    /// A pinned index is out of range.
    #[error("pinned particle index {index} is out of range for {count} particles")]
    PinOutOfRange {
        /// The bad index.
        index: usize,
        /// Particle count.
        count: usize,
    },
}

/// Builds a strand and its particles in one call.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy::math::DVec2;
/// # use bevy_strands::prelude::*;
/// fn spawn_rope(mut commands: Commands) {
///     // 30 particles, 0.02 apart, hanging from a pinned first particle.
///     StrandBuilder::line(DVec2::new(0.5, 0.9), DVec2::NEG_Y, 30, 0.02)
///         .pin_first()
///         .spawn(&mut commands)
///         .expect("a valid strand");
/// }
/// ```
#[derive(Clone, Debug)]
pub struct StrandBuilder {
    points: Vec<DVec2>,
    closed: bool,
    mass: f64,
    velocity: DVec2,
    velocities: Option<Vec<DVec2>>,
    pinned: Vec<usize>,
    rest_lengths: Option<Vec<f64>>,
    rest_shape_from_points: bool,
    material: Option<StrandMaterial>,
    kind: StrandKind,
}

impl StrandBuilder {
    /// A strand through the given points, in order.
    pub fn polyline(points: impl IntoIterator<Item = DVec2>) -> Self {
        Self {
            points: points.into_iter().collect(),
            closed: false,
            mass: 1.0,
            velocity: DVec2::ZERO,
            velocities: None,
            pinned: Vec::new(),
            rest_lengths: None,
            rest_shape_from_points: false,
            material: None,
            kind: StrandKind::Rope,
        }
    }

    /// `count` particles from `start`, `spacing` apart along `direction` (normalized here).
    pub fn line(start: DVec2, direction: DVec2, count: usize, spacing: f64) -> Self {
        let step = direction.normalize_or_zero() * spacing;
        Self::polyline((0..count).map(move |i| start + step * i as f64))
    }

    /// A closed loop through the given points (the last joins the first).
    pub fn closed_loop(points: impl IntoIterator<Item = DVec2>) -> Self {
        Self::polyline(points).closed(true).rest_shape_from_points()
    }

    /// Whether the last particle joins the first.
    pub fn closed(mut self, closed: bool) -> Self {
        self.closed = closed;
        self
    }

    /// Mass of every particle (default 1).
    pub fn mass(mut self, mass: f64) -> Self {
        self.mass = mass;
        self
    }

    /// Initial velocity of every particle.
    pub fn velocity(mut self, velocity: DVec2) -> Self {
        self.velocity = velocity;
        self
    }

    /// Initial velocity of each particle, in order (overrides [`StrandBuilder::velocity`]).
    pub fn velocities(mut self, velocities: Vec<DVec2>) -> Self {
        self.velocities = Some(velocities);
        self
    }

    /// Pin the particle at `index`.
    pub fn pin(mut self, index: usize) -> Self {
        self.pinned.push(index);
        self
    }

    /// Pin the first particle.
    pub fn pin_first(self) -> Self {
        self.pin(0)
    }

    /// Pin the last particle.
    pub fn pin_last(self) -> Self {
        let last = self.points.len().saturating_sub(1);
        self.pin(last)
    }

    /// Rest lengths of the edges, instead of the distances between the points (a strand
    /// that starts stretched or compressed).
    pub fn rest_lengths(mut self, rest_lengths: Vec<f64>) -> Self {
        self.rest_lengths = Some(rest_lengths);
        self
    }

    /// Take the rest turning angles from the given points instead of straight.
    pub fn rest_shape_from_points(mut self) -> Self {
        self.rest_shape_from_points = true;
        self
    }

    /// Material of the strand's springs and bending.
    pub fn material(mut self, material: StrandMaterial) -> Self {
        self.material = Some(material);
        self
    }

    /// What the strand represents.
    pub fn kind(mut self, kind: StrandKind) -> Self {
        self.kind = kind;
        self
    }

    /// Check the description and compute rest lengths and angles.
    /// The particles' positions, in order.
    pub fn points(&self) -> &[DVec2] {
        &self.points
    }

    pub fn validate(&self) -> Result<(Vec<f64>, Vec<f64>), StrandError> {
        let n = self.points.len();
        let (kind, min) = if self.closed {
            ("closed", 3)
        } else {
            ("open", 2)
        };
        if n < min {
            return Err(StrandError::TooFewParticles { kind, min, got: n });
        }
        for (index, &p) in self.points.iter().enumerate() {
            if !p.is_finite() {
                return Err(StrandError::NotFinite {
                    what: "position",
                    index,
                    value: p,
                });
            }
        }
        if !self.velocity.is_finite() {
            return Err(StrandError::NotFinite {
                what: "velocity",
                index: 0,
                value: self.velocity,
            });
        }
        if let Some(velocities) = &self.velocities {
            if velocities.len() != n {
                return Err(StrandError::WrongLength {
                    what: "velocities",
                    got: velocities.len(),
                    expected: n,
                });
            }
            if let Some((index, &value)) =
                velocities.iter().enumerate().find(|(_, v)| !v.is_finite())
            {
                return Err(StrandError::NotFinite {
                    what: "velocity",
                    index,
                    value,
                });
            }
        }
        if !(self.mass.is_finite() && self.mass > 0.0) {
            return Err(StrandError::BadMass {
                index: 0,
                value: self.mass,
            });
        }
        if let Some(&index) = self.pinned.iter().find(|&&i| i >= n) {
            return Err(StrandError::PinOutOfRange { index, count: n });
        }
        let distances = rest_lengths_of(&self.points, self.closed)?;
        let rest_lengths = match &self.rest_lengths {
            None => distances,
            Some(given) if given.len() != distances.len() => {
                return Err(StrandError::WrongLength {
                    what: "rest lengths",
                    got: given.len(),
                    expected: distances.len(),
                });
            }
            Some(given) => {
                if let Some((edge, &value)) = given
                    .iter()
                    .enumerate()
                    .find(|(_, l)| !(l.is_finite() && **l > 0.0))
                {
                    return Err(StrandError::BadRestLength { edge, value });
                }
                given.clone()
            }
        };
        let rest_angles = if self.rest_shape_from_points {
            turning_angles(&self.points, self.closed)
        } else {
            Vec::new()
        };
        Ok((rest_lengths, rest_angles))
    }

    /// Spawn the strand and its particles. Nothing is spawned if the description is
    /// invalid.
    pub fn spawn(self, commands: &mut Commands) -> Result<Entity, StrandError> {
        let (rest_lengths, rest_angles) = self.validate()?;
        let strand = commands.spawn(self.kind).id();
        let particles: Vec<Entity> = self
            .points
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                let velocity = self.velocities.as_ref().map_or(self.velocity, |v| v[i]);
                let mut particle = commands.spawn((
                    Particle,
                    Position(p),
                    Velocity(velocity),
                    Mass(self.mass),
                    StrandOf(strand),
                ));
                if self.pinned.contains(&i) {
                    particle.insert(Pinned);
                }
                particle.id()
            })
            .collect();
        let mut entity = commands.entity(strand);
        entity.insert(Strand {
            particles,
            rest_lengths,
            rest_angles,
            closed: self.closed,
        });
        if let Some(material) = self.material {
            entity.insert(material);
        }
        Ok(strand)
    }

    /// Spawn directly into a world (tests, set-up code).
    pub fn spawn_in(self, world: &mut World) -> Result<Entity, StrandError> {
        let mut commands = world.commands();
        let strand = self.spawn(&mut commands);
        world.flush();
        strand
    }
}

/// Rest lengths of the edges through `points`, refusing coincident neighbours.
pub fn rest_lengths_of(points: &[DVec2], closed: bool) -> Result<Vec<f64>, StrandError> {
    let n = points.len();
    (0..edge_count(n, closed))
        .map(|k| {
            let (a, b) = (points[k], points[(k + 1) % n]);
            let length = a.distance(b);
            if length > 0.0 && length.is_finite() {
                Ok(length)
            } else {
                Err(StrandError::CoincidentParticles {
                    a: k,
                    b: (k + 1) % n,
                    at: a,
                })
            }
        })
        .collect()
}

/// Signed turning angle (radians) from edge `incoming` to edge `outgoing`.
pub fn turning_angle(incoming: DVec2, outgoing: DVec2) -> f64 {
    incoming.perp_dot(outgoing).atan2(incoming.dot(outgoing))
}

/// Turning angles at every bending vertex of the polyline.
pub fn turning_angles(points: &[DVec2], closed: bool) -> Vec<f64> {
    let n = points.len();
    (0..bend_count(n, closed))
        .map(|k| {
            let s = if closed { k } else { k + 1 };
            let prev = points[(s + n - 1) % n];
            let next = points[(s + 1) % n];
            turning_angle(points[s] - prev, next - points[s])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builder_refuses_bad_strands() {
        let one = StrandBuilder::polyline([DVec2::ZERO]);
        assert!(matches!(
            one.validate(),
            Err(StrandError::TooFewParticles { got: 1, .. })
        ));
        let coincident = StrandBuilder::polyline([DVec2::ZERO, DVec2::X, DVec2::X]);
        assert!(matches!(
            coincident.validate(),
            Err(StrandError::CoincidentParticles { a: 1, b: 2, .. })
        ));
        let nan = StrandBuilder::polyline([DVec2::ZERO, DVec2::new(f64::NAN, 0.0)]);
        assert!(matches!(
            nan.validate(),
            Err(StrandError::NotFinite { index: 1, .. })
        ));
        let heavy = StrandBuilder::polyline([DVec2::ZERO, DVec2::X]).mass(-1.0);
        assert!(matches!(heavy.validate(), Err(StrandError::BadMass { .. })));
        let rest = StrandBuilder::polyline([DVec2::ZERO, DVec2::X]).rest_lengths(vec![0.0]);
        assert!(matches!(
            rest.validate(),
            Err(StrandError::BadRestLength { edge: 0, .. })
        ));
        let pin = StrandBuilder::polyline([DVec2::ZERO, DVec2::X]).pin(5);
        assert!(matches!(
            pin.validate(),
            Err(StrandError::PinOutOfRange { index: 5, .. })
        ));
    }

    #[test]
    fn rest_shape_of_a_triangle() {
        let tri = [DVec2::ZERO, DVec2::X, DVec2::new(0.5, 3f64.sqrt() / 2.0)];
        let angles = turning_angles(&tri, true);
        for a in angles {
            assert!((a - 2.0 * std::f64::consts::PI / 3.0).abs() < 1e-12);
        }
        let lengths = rest_lengths_of(&tri, true).unwrap();
        assert!(lengths.iter().all(|l| (l - 1.0).abs() < 1e-12));
    }
}
