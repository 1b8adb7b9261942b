//! The furry creature: a disc body on a scripted circular path, with hairs rooted on
//! its rim. Each hair's first two particles (its root and first edge) move rigidly with
//! the body, so the hair keeps its root position and orientation; the rest is free.

use std::f64::consts::TAU;

use bevy::math::DVec2;
use bevy::prelude::*;

use bevy_strands::prelude::*;

use super::Disc;

/// A body moving on a circle, driving its hairs' roots.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component)]
pub struct FurryCreature {
    /// Centre of the body's circular path.
    pub centre: DVec2,
    /// Radius of the path.
    pub path_radius: f64,
    /// Seconds per turn of the path.
    pub period: f64,
    /// Radius of the body.
    pub body_radius: f64,
    /// Each driven particle and its offset from the body's centre.
    pub roots: Vec<(Entity, DVec2)>,
    /// Packed indices of `roots`, for the topology version in `cached_version`.
    #[reflect(ignore)]
    cached: Vec<(u32, DVec2)>,
    #[reflect(ignore)]
    cached_version: u64,
}

impl FurryCreature {
    /// The body's centre at simulated time `t`.
    pub fn body_centre(&self, t: f64) -> DVec2 {
        self.centre + self.path_radius * DVec2::from_angle(TAU * t / self.period)
    }
}

/// Spawn a creature with `hairs` hairs of `particles` particles, `spacing` apart,
/// rooted evenly around the body's rim and pointing outwards.
pub fn spawn_furry_creature(
    world: &mut World,
    creature: FurryCreature,
    hairs: usize,
    particles: usize,
    spacing: f64,
    mass: f64,
) -> Entity {
    let start = creature.body_centre(0.0);
    let mut roots = Vec::with_capacity(2 * hairs);
    for i in 0..hairs {
        let outward = DVec2::from_angle(TAU * i as f64 / hairs as f64);
        let strand = StrandBuilder::line(
            start + creature.body_radius * outward,
            outward,
            particles,
            spacing,
        )
        .pin(0)
        .pin(1)
        .mass(mass)
        .kind(StrandKind::Hair)
        .spawn_in(world)
        .expect("a hair of at least two particles with positive spacing is valid");
        let hair = &world.get::<Strand>(strand).expect("just spawned").particles;
        for (k, &particle) in hair[..2].iter().enumerate() {
            roots.push((
                particle,
                (creature.body_radius + k as f64 * spacing) * outward,
            ));
        }
    }
    let disc = Disc {
        centre: start,
        radius: creature.body_radius,
    };
    world
        .spawn((FurryCreature { roots, ..creature }, disc))
        .id()
}

impl FurryCreature {
    /// A creature with no hairs yet (see [`spawn_furry_creature`]).
    pub fn new(centre: DVec2, path_radius: f64, period: f64, body_radius: f64) -> Self {
        Self {
            centre,
            path_radius,
            period,
            body_radius,
            roots: Vec::new(),
            cached: Vec::new(),
            cached_version: u64::MAX,
        }
    }
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
        let target = creature.body_centre(clock.time + dt);
        for &(i, offset) in &creature.cached {
            let i = i as usize;
            state.velocity[i] = (target + offset - state.position[i]) / dt;
        }
        disc.centre = creature.body_centre(clock.time);
    }
}
