//! Editing operations on a world: create a particle, join two particles with an edge,
//! draw a strand along a path, pin or unpin, delete, and find the particle nearest a
//! point. Any front end (a demo's mouse tools, tests, a game's own input) edits the
//! simulation through these.

use bevy::math::DVec2;
use bevy::prelude::*;
use thiserror::Error;

use crate::model::queries::{EdgeHit, nearest_edge, ray_cast};
use crate::model::validate::{StrandError, rest_lengths_of};
use crate::world::builder::StrandBuilder;
use crate::world::particle::{Particle, Pinned, Position, Velocity};
use crate::world::state::ParticleState;
use crate::world::strand::{Strand, StrandKind};
use crate::world::topology::{Topology, cut_strand, split_strand};

/// Why an editing operation did nothing.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ToolError {
    /// The entity is not a particle.
    #[error("{0} is not a particle")]
    NotAParticle(Entity),
    /// An edge needs two different particles.
    #[error("an edge needs two different particles")]
    SameParticle,
    /// The strand has no such edge (or is not a strand).
    #[error("{0} has no edge {1}")]
    NoSuchEdge(Entity, usize),
    /// The two particles are already joined by an edge.
    #[error("{0} and {1} are already joined by an edge")]
    AlreadyJoined(Entity, Entity),
    /// Fewer particles than needed.
    #[error("need at least {needed} particles, found {found}")]
    TooFewParticles {
        /// How many are needed.
        needed: usize,
        /// How many there are.
        found: usize,
    },
    /// The strand could not be built.
    #[error(transparent)]
    Strand(#[from] StrandError),
}

/// The particles nearest to `point`, closest first, at most `count` of them, within
/// `within` (world units).
pub fn nearest_particles(
    world: &mut World,
    point: DVec2,
    within: f64,
    count: usize,
) -> Vec<Entity> {
    let mut query = world.query_filtered::<(Entity, &Position), With<Particle>>();
    let mut found: Vec<(f64, Entity)> = query
        .iter(world)
        .map(|(e, p)| (p.0.distance(point), e))
        .filter(|(d, _)| *d <= within)
        .collect();
    found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    found.into_iter().take(count).map(|(_, e)| e).collect()
}

/// The particle nearest to `point` within `within`.
pub fn nearest_particle(world: &mut World, point: DVec2, within: f64) -> Option<Entity> {
    nearest_particles(world, point, within, 1)
        .into_iter()
        .next()
}

/// A particle at rest at `point`.
pub fn create_particle(world: &mut World, point: DVec2) -> Entity {
    world
        .spawn((Particle, Position(point), Velocity(DVec2::ZERO)))
        .id()
}

/// Join `a` and `b` with an edge (a new two-particle strand) at their current distance.
pub fn create_edge(world: &mut World, a: Entity, b: Entity) -> Result<Entity, ToolError> {
    if a == b {
        return Err(ToolError::SameParticle);
    }
    let position = |world: &World, e: Entity| {
        world
            .get::<Position>(e)
            .filter(|_| world.get::<Particle>(e).is_some())
            .map(|p| p.0)
            .ok_or(ToolError::NotAParticle(e))
    };
    let (pa, pb) = (position(world, a)?, position(world, b)?);
    let mut strands = world.query::<&Strand>();
    if strands.iter(world).any(|s| s.joins(a, b)) {
        return Err(ToolError::AlreadyJoined(a, b));
    }
    let rest_lengths = rest_lengths_of(&[pa, pb], false)?;
    Ok(world
        .spawn((
            Strand {
                particles: vec![a, b],
                rest_lengths,
                rest_angles: Vec::new(),
                closed: false,
            },
            StrandKind::Rope,
        ))
        .id())
}

/// Join the two particles nearest to `point` (within `within`) with an edge.
pub fn create_edge_near(world: &mut World, point: DVec2, within: f64) -> Result<Entity, ToolError> {
    match nearest_particles(world, point, within, 2)[..] {
        [a, b] => create_edge(world, a, b),
        ref found => Err(ToolError::TooFewParticles {
            needed: 2,
            found: found.len(),
        }),
    }
}

/// Points along `path`, `spacing` apart in arc length, starting at its first point (a
/// drawn stroke becomes evenly spaced particles). The remainder shorter than `spacing`
/// at the end is dropped.
pub fn resample_polyline(path: &[DVec2], spacing: f64) -> Vec<DVec2> {
    let Some(&first) = path.first() else {
        return Vec::new();
    };
    let mut out = vec![first];
    if spacing.is_nan() || spacing <= 0.0 {
        return out;
    }
    let mut last = first;
    for window in path.windows(2) {
        let (from, to) = (window[0], window[1]);
        // Place every point on this segment that is `spacing` from the last placed one.
        let mut start = from;
        loop {
            let d = to - start;
            let f = start - last;
            // |f + t d| = spacing, t ∈ [0, 1]: the far root of a quadratic in t.
            let (a, b, c) = (
                d.length_squared(),
                2.0 * f.dot(d),
                f.length_squared() - spacing * spacing,
            );
            if a == 0.0 {
                break;
            }
            let disc = b * b - 4.0 * a * c;
            if disc < 0.0 {
                break;
            }
            let t = (-b + disc.sqrt()) / (2.0 * a);
            if !(0.0..=1.0).contains(&t) {
                break;
            }
            let point = start + t * d;
            out.push(point);
            last = point;
            start = point;
        }
    }
    out
}

/// A strand along a drawn `path`, resampled to `spacing`; its first particle is pinned
/// when `pin_root` (a hair drawn from its root).
pub fn draw_strand(
    world: &mut World,
    path: &[DVec2],
    spacing: f64,
    pin_root: bool,
    kind: StrandKind,
) -> Result<Entity, ToolError> {
    let points = resample_polyline(path, spacing);
    if points.len() < 2 {
        return Err(ToolError::TooFewParticles {
            needed: 2,
            found: points.len(),
        });
    }
    let mut builder = StrandBuilder::polyline(points).kind(kind);
    if pin_root {
        builder = builder.pin_first();
    }
    Ok(builder.spawn_in(world)?)
}

/// Pin a free particle or free a pinned one; returns whether it is now pinned.
pub fn toggle_pin(world: &mut World, particle: Entity) -> Result<bool, ToolError> {
    if world.get::<Particle>(particle).is_none() {
        return Err(ToolError::NotAParticle(particle));
    }
    let mut entity = world.entity_mut(particle);
    if entity.contains::<Pinned>() {
        entity.remove::<Pinned>();
        Ok(false)
    } else {
        entity.insert((Pinned, Velocity(DVec2::ZERO)));
        Ok(true)
    }
}

/// A strand edge a query met.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrandHit {
    /// The strand.
    pub strand: Entity,
    /// The edge's number along it.
    pub edge: usize,
    /// The edge's two particles.
    pub particles: [Entity; 2],
    /// The point met, where along the edge (0 at its first particle), and the distance
    /// (along the ray, or from the point).
    pub hit: EdgeHit,
}

fn strand_hit(world: &World, hit: EdgeHit) -> Option<StrandHit> {
    let topology = world.get_resource::<Topology>()?;
    let state = world.get_resource::<ParticleState>()?;
    let edge = topology.edges.get(hit.edge as usize)?;
    let record = topology.strands.get(edge.strand as usize)?;
    Some(StrandHit {
        strand: record.entity,
        edge: hit.edge as usize - record.edges.start,
        particles: [state.entity[edge.a as usize], state.entity[edge.b as usize]],
        hit,
    })
}

/// The first strand edge the ray from `origin` along `direction` meets within
/// `max_distance` (a grappling hook's line), at the last tick's positions.
pub fn ray_cast_strands(
    world: &World,
    origin: DVec2,
    direction: DVec2,
    max_distance: f64,
) -> Option<StrandHit> {
    let topology = world.get_resource::<Topology>()?;
    let state = world.get_resource::<ParticleState>()?;
    let hit = ray_cast(
        &topology.edges,
        &state.position,
        origin,
        direction,
        max_distance,
    )?;
    strand_hit(world, hit)
}

/// The strand edge nearest `point` within `within`, at the last tick's positions.
pub fn nearest_strand_edge(world: &World, point: DVec2, within: f64) -> Option<StrandHit> {
    let topology = world.get_resource::<Topology>()?;
    let state = world.get_resource::<ParticleState>()?;
    let hit = nearest_edge(&topology.edges, &state.position, point, within)?;
    strand_hit(world, hit)
}

/// Cut edge `edge` of `strand` at run time: an open strand becomes two (a piece of one
/// particle leaves it loose), a loop opens. Returns the strands left.
pub fn cut_edge(world: &mut World, strand: Entity, edge: usize) -> Result<usize, ToolError> {
    cut_strand(world, strand, edge).ok_or(ToolError::NoSuchEdge(strand, edge))
}

/// Delete a particle. Every strand through it is split around it first, so that no
/// strand is left referencing it; pieces too short to be strands go.
pub fn delete_particle(world: &mut World, particle: Entity) -> Result<(), ToolError> {
    if world.get::<Particle>(particle).is_none() {
        return Err(ToolError::NotAParticle(particle));
    }
    let mut strands = world.query::<(Entity, &Strand)>();
    let through: Vec<Entity> = strands
        .iter(world)
        .filter(|(_, s)| s.particles.contains(&particle))
        .map(|(e, _)| e)
        .collect();
    for strand in through {
        split_strand(world, strand, |p| p != particle);
    }
    world.despawn(particle);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drawn_path_is_resampled_to_the_spacing() {
        // An L-shaped stroke of length 0.3 + 0.2.
        let path = [DVec2::ZERO, DVec2::new(0.3, 0.0), DVec2::new(0.3, 0.2)];
        let points = resample_polyline(&path, 0.05);
        for w in points.windows(2) {
            assert!((w[0].distance(w[1]) - 0.05).abs() < 1e-12, "{points:?}");
        }
        // Cutting the corner makes the chord path a little shorter than the stroke.
        assert!(points.len() >= 9 && points.len() <= 11, "{}", points.len());
        assert!(points.last().unwrap().distance(DVec2::new(0.3, 0.2)) < 0.05);
        // A dense, jittery stroke along a line gives the same spacing.
        let jitter: Vec<DVec2> = (0..=1000)
            .map(|i| DVec2::new(i as f64 * 1e-3, 1e-5 * (i as f64).sin()))
            .collect();
        let points = resample_polyline(&jitter, 0.1);
        assert_eq!(points.len(), 11);
    }
}
