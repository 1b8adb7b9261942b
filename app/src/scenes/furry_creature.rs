//! The furry creature: a disc body on a scripted circular path, with hairs rooted on
//! its rim. Each hair's first two particles (its root and first edge) move rigidly with
//! the body, so the hair keeps its root position and orientation; the rest is free.

use std::f64::consts::TAU;

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::colliders::outline;
use bevy_strands::prelude::*;
use serde::{Deserialize, Serialize};

use super::Disc;

/// What a furry creature is: the scenario file's `furry_creature` section.
#[derive(Serialize, Deserialize, Reflect, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FurryCreatureSpec {
    /// Centre of the body's circular path.
    pub centre: DVec2,
    /// Radius of the path.
    pub path_radius: f64,
    /// Seconds per turn of the path.
    pub period: f64,
    /// Radius of the body.
    pub body_radius: f64,
    /// Hairs, evenly spaced around the rim.
    pub hairs: usize,
    /// Particles per hair.
    pub particles_per_hair: usize,
    /// Rest spacing of the hairs' particles.
    pub spacing: f64,
    /// Mass of each particle.
    #[serde(default = "one")]
    pub mass: f64,
    /// Hairs collide with the body when set: its collision outline, a driven wall
    /// polygon around the centre, stands this far inside the rim, so the roots (which
    /// cannot move off the rim) never touch it. Unset, hairs pass over the body.
    #[serde(default)]
    pub body_inset: Option<f64>,
}

/// Largest gap between the body's collision polygon and its circle.
const OUTLINE_TOLERANCE: f64 = 1e-4;

fn one() -> f64 {
    1.0
}

impl FurryCreatureSpec {
    /// The body's centre at simulated time `t`.
    pub fn body_centre(&self, t: f64) -> DVec2 {
        self.centre + self.path_radius * DVec2::from_angle(TAU * t / self.period)
    }
}

/// A body moving on a circle, driving its hairs' roots.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component)]
pub struct FurryCreature {
    /// The body, its path and its hairs.
    pub spec: FurryCreatureSpec,
    /// Each driven particle and its offset from the body's centre.
    pub roots: Vec<(Entity, DVec2)>,
    /// Packed indices of `roots`, for the topology version in `cached_version`.
    #[reflect(ignore)]
    cached: Vec<(u32, DVec2)>,
    #[reflect(ignore)]
    cached_version: u64,
}

impl FurryCreature {
    /// A creature driving `roots` (particle, offset from the body's centre).
    pub fn new(spec: FurryCreatureSpec, roots: Vec<(Entity, DVec2)>) -> Self {
        Self {
            spec,
            roots,
            cached: Vec::new(),
            cached_version: u64::MAX,
        }
    }

    /// The creature's body as drawn at simulated time `t`.
    pub fn disc(&self, t: f64) -> Disc {
        Disc {
            centre: self.spec.body_centre(t),
            radius: self.spec.body_radius,
        }
    }
}

/// Spawn a creature: its hairs rooted evenly around the body's rim, pointing outwards.
pub fn spawn_furry_creature(world: &mut World, spec: FurryCreatureSpec) -> Entity {
    let start = spec.body_centre(0.0);
    let mut roots = Vec::with_capacity(2 * spec.hairs);
    for i in 0..spec.hairs {
        let outward = DVec2::from_angle(TAU * i as f64 / spec.hairs as f64);
        let spawned = StrandBuilder::line(
            start + spec.body_radius * outward,
            outward,
            spec.particles_per_hair,
            spec.spacing,
        )
        .pin(0)
        .pin(1)
        .mass(spec.mass)
        .kind(StrandKind::Hair)
        .spawn_in(world);
        let strand = match spawned {
            Ok(strand) => strand,
            Err(e) => {
                error!("furry creature: hair {i} was refused: {e}");
                continue;
            }
        };
        let hair = &world.get::<Strand>(strand).expect("just spawned").particles;
        for (k, &particle) in hair[..2].iter().enumerate() {
            roots.push((
                particle,
                (spec.body_radius + k as f64 * spec.spacing) * outward,
            ));
        }
    }
    if let Some(inset) = spec.body_inset {
        match spawn_body_outline(world, &spec, spec.body_radius - inset) {
            Ok(outline) => roots.extend(outline),
            Err(e) => error!("furry creature: the body's outline was refused: {e}"),
        }
    }
    let creature = FurryCreature::new(spec, roots);
    let disc = creature.disc(0.0);
    world.spawn((creature, disc)).id()
}

/// The body's collision outline: a pinned wall polygon circumscribing the circle of
/// `radius` about the body's centre (the library's collider outline, within
/// [`OUTLINE_TOLERANCE`]), driven like the roots. Returns its particles and their
/// offsets from the centre.
fn spawn_body_outline(
    world: &mut World,
    spec: &FurryCreatureSpec,
    radius: f64,
) -> Result<Vec<(Entity, DVec2)>, String> {
    if !radius.is_finite() || radius <= 0.0 {
        return Err(format!("body_inset leaves a radius of {radius}"));
    }
    let circle = ColliderShape::Circle {
        radius: radius as f32,
    };
    let (corners, _) = outline(&circle, OUTLINE_TOLERANCE as f32);
    let offsets: Vec<DVec2> = corners.iter().map(|c| c.as_dvec2()).collect();
    let start = spec.body_centre(0.0);
    let mut builder = StrandBuilder::closed_loop(offsets.iter().map(|&o| start + o))
        .kind(StrandKind::Wall)
        .material(StrandMaterial::INERT);
    for k in 0..offsets.len() {
        builder = builder.pin(k);
    }
    let strand = builder.spawn_in(world).map_err(|e| e.to_string())?;
    let particles = &world.get::<Strand>(strand).expect("just spawned").particles;
    Ok(particles.iter().copied().zip(offsets).collect())
}

/// Give every root the velocity that lands it on the body's path at the end of the
/// step (pinned particles move by their own velocity).
pub fn drive_furry_creatures(
    config: Res<StrandsConfig>,
    clock: Res<SimulationClock>,
    topology: Res<Topology>,
    mut state: ResMut<ParticleState>,
    mut creatures: Query<(&mut FurryCreature, &mut Disc)>,
) {
    let dt = config.dt;
    for (mut creature, mut disc) in &mut creatures {
        if creature.cached_version != topology.version {
            let cached = creature
                .roots
                .iter()
                .filter_map(|(entity, offset)| topology.index.get(entity).map(|&i| (i, *offset)))
                .collect();
            creature.cached = cached;
            creature.cached_version = topology.version;
        }
        let target = creature.spec.body_centre(clock.time + dt);
        for &(i, offset) in &creature.cached {
            let i = i as usize;
            state.velocity[i] = (target + offset - state.position[i]) / dt;
        }
        *disc = creature.disc(clock.time);
    }
}
