//! [`StrandBuilder`]: a strand and its particles described, checked and spawned in one
//! call.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::model::geometry::turning_angles;
use crate::model::validate::{
    MAX_STRAND_PARTICLES, StrandError, check_particle, check_particle_count, check_strand_shape,
    rest_lengths_of,
};
use crate::world::particle::{Mass, Particle, Pinned, Position, Velocity};
use crate::world::strand::{Strand, StrandKind, StrandMaterial, StrandOf};

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

/// What a valid description builds: the strand's rest lengths and rest angles.
#[derive(Clone, Debug, PartialEq)]
pub struct RestShape {
    /// Rest length of each edge.
    pub rest_lengths: Vec<f64>,
    /// Rest turning angle at each bending vertex (empty: straight).
    pub rest_angles: Vec<f64>,
}

impl StrandBuilder {
    /// A strand through the given points, in order.
    pub fn polyline(points: impl IntoIterator<Item = DVec2>) -> Self {
        // One past the cap is enough to know it is too many.
        let points = points.into_iter().take(MAX_STRAND_PARTICLES + 1).collect();
        Self {
            points,
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
        // More than the cap is refused by `validate`; do not build them first.
        let count = count.min(MAX_STRAND_PARTICLES + 1);
        let step = direction.normalize_or_zero() * spacing;
        Self::polyline((0..count).map(move |i| start + step * i as f64))
    }

    /// A rope hung between `a` and `b`, pinned at both: `count` particles on a parabola
    /// `slack` times as long as the gap (a rope bridge, a washing line).
    pub fn hanging(a: DVec2, b: DVec2, count: usize, slack: f64) -> Self {
        let count = count.clamp(2, MAX_STRAND_PARTICLES + 1);
        let span = a.distance(b);
        // A parabola of depth d is about span (1 + 8 d² / (3 span²)) long.
        let depth = span * ((slack.max(1.0) - 1.0) * 3.0 / 8.0).sqrt();
        let last = (count - 1) as f64;
        Self::polyline((0..count).map(move |i| {
            let t = i as f64 / last;
            a.lerp(b, t) - DVec2::Y * 4.0 * depth * t * (1.0 - t)
        }))
        .pin(0)
        .pin(count - 1)
    }

    /// A closed loop through the given points (the last joins the first), keeping their
    /// shape at rest.
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

    /// The particles' positions, in order.
    pub fn points(&self) -> &[DVec2] {
        &self.points
    }

    /// Whether the strand is a loop (its last particle joined to its first).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    fn velocity_of(&self, i: usize) -> DVec2 {
        self.velocities.as_ref().map_or(self.velocity, |v| v[i])
    }

    /// Check the description with the same rules the topology applies to strands at
    /// run time, and compute its rest lengths and angles.
    pub fn validate(&self) -> Result<RestShape, StrandError> {
        let n = self.points.len();
        if n > MAX_STRAND_PARTICLES {
            return Err(StrandError::TooManyParticles {
                max: MAX_STRAND_PARTICLES,
            });
        }
        check_particle_count(n, self.closed)?;
        if let Some(velocities) = &self.velocities
            && velocities.len() != n
        {
            return Err(StrandError::WrongLength {
                what: "velocities",
                got: velocities.len(),
                expected: n,
            });
        }
        if let Some(&index) = self.pinned.iter().find(|&&i| i >= n) {
            return Err(StrandError::PinOutOfRange { index, count: n });
        }
        for (index, &point) in self.points.iter().enumerate() {
            let pinned = self.pinned.contains(&index);
            check_particle(point, self.velocity_of(index), self.mass, pinned)
                .map_err(|problem| StrandError::Particle { index, problem })?;
        }
        let distances = rest_lengths_of(&self.points, self.closed)?;
        let rest_lengths = self.rest_lengths.clone().unwrap_or(distances);
        let rest_angles = if self.rest_shape_from_points {
            turning_angles(&self.points, self.closed)
        } else {
            Vec::new()
        };
        check_strand_shape(n, self.closed, &rest_lengths, &rest_angles)?;
        Ok(RestShape {
            rest_lengths,
            rest_angles,
        })
    }

    /// Spawn the strand and its particles. Nothing is spawned if the description is
    /// invalid.
    pub fn spawn(self, commands: &mut Commands) -> Result<Entity, StrandError> {
        let RestShape {
            rest_lengths,
            rest_angles,
        } = self.validate()?;
        let strand = commands.spawn(self.kind).id();
        let particles: Vec<Entity> = self
            .points
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                let mut particle = commands.spawn((
                    Particle,
                    Position(p),
                    Velocity(self.velocity_of(i)),
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
            Err(StrandError::Particle { index: 1, .. })
        ));
        let heavy = StrandBuilder::polyline([DVec2::ZERO, DVec2::X]).mass(-1.0);
        assert!(matches!(
            heavy.validate(),
            Err(StrandError::Particle { index: 0, .. })
        ));
        let rest = StrandBuilder::polyline([DVec2::ZERO, DVec2::X]).rest_lengths(vec![0.0]);
        assert!(matches!(
            rest.validate(),
            Err(StrandError::BadRestLength { edge: 0, .. })
        ));
        let wrong = StrandBuilder::polyline([DVec2::ZERO, DVec2::X]).rest_lengths(vec![1.0; 2]);
        assert!(matches!(
            wrong.validate(),
            Err(StrandError::WrongLength { expected: 1, .. })
        ));
        let pin = StrandBuilder::polyline([DVec2::ZERO, DVec2::X]).pin(5);
        assert!(matches!(
            pin.validate(),
            Err(StrandError::PinOutOfRange { index: 5, .. })
        ));
    }

    #[test]
    fn a_closed_loop_keeps_its_shape_at_rest() {
        let tri = [DVec2::ZERO, DVec2::X, DVec2::new(0.5, 3f64.sqrt() / 2.0)];
        let shape = StrandBuilder::closed_loop(tri).validate().unwrap();
        assert!(shape.rest_lengths.iter().all(|l| (l - 1.0).abs() < 1e-12));
        assert_eq!(shape.rest_angles.len(), 3);
    }
}
