//! Spawning a validated scenario into a world.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::world::edit::create_edge;

use crate::initial_state::{SceneItems, check_initial_state};
use crate::scenario::{Scenario, ScenarioError, vec2};
use crate::scenes::drain::Drain;
use crate::scenes::furry_creature::spawn_furry_creature;
use crate::scenes::meatball_factory::MeatballFactory;
use crate::scenes::spaghetti_factory::SpaghettiFactory;

/// Set the world's configuration resources to the scenario's.
pub fn configure(world: &mut World, scenario: &Scenario) {
    let mut step = scenario.step.clone();
    // The scene's cap holds for the particles its factories add later too.
    step.max_particles = scenario.max_particles;
    step.max_edges = scenario.max_particles.saturating_mul(2);
    world.insert_resource(step);
    world.insert_resource(scenario.constraints.clone());
    world.insert_resource(scenario.collisions.clone());
    world.insert_resource(scenario.contact.clone());
}

/// Configure the world from the scenario and spawn its walls, strands, particles and
/// factories. The scenario must have passed [`Scenario::validate`].
pub fn spawn_scenario(world: &mut World, scene: &Scenario) -> Result<(), ScenarioError> {
    let fail = |item: String, problem: String| ScenarioError::new(scene.origin(), item, problem);
    configure(world, scene);
    let mut items = SceneItems::default();

    if let Some(scale) = &scene.scale {
        let container = scale.container();
        let walls = container_builder(vec2(container.min), vec2(container.max))
            .spawn_in(world)
            .map_err(|e| fail("scale".into(), e.to_string()))?;
        items.name(walls, "the container");
        let step = DVec2::new(scale.spacing, 0.0);
        for s in 0..scale.strands {
            let start = scale.start(s);
            // A gentle wave so that strands do not land perfectly flat on each other.
            let points = (0..scale.particles).map(|i| {
                let wave = scale.wave() * ((i + 3 * s) as f64 * 0.4).sin();
                start + step * i as f64 + DVec2::new(0.0, wave)
            });
            let strand = StrandBuilder::polyline(points)
                .kind(StrandKind::Rope)
                .spawn_in(world)
                .map_err(|e| fail(format!("scale strand {s}"), e.to_string()))?;
            items.name(strand, format!("scale strand {s}"));
        }
    } else if let Some(container) = &scene.container {
        let walls = container_builder(vec2(container.min), vec2(container.max))
            .spawn_in(world)
            .map_err(|e| fail("container".into(), e.to_string()))?;
        items.name(walls, "the container");
    }
    let mut strands = Vec::with_capacity(scene.strands.len());
    for (i, strand) in scene.strands.iter().enumerate() {
        let entity = strand
            .builder()
            .spawn_in(world)
            .map_err(|e| fail(format!("strands[{i}]"), e.to_string()))?;
        items.name(entity, format!("strands[{i}]"));
        strands.push(entity);
    }
    for (i, link) in scene.links.iter().enumerate() {
        let particle = |(strand, particle): (usize, usize)| {
            strands
                .get(strand)
                .and_then(|&s| world.get::<Strand>(s))
                .and_then(|s| s.particles.get(particle).copied())
                .ok_or_else(|| {
                    fail(
                        format!("links[{i}]"),
                        format!("no particle {particle} in strand {strand}"),
                    )
                })
        };
        let (a, b) = (particle(link.from)?, particle(link.to)?);
        let link =
            create_edge(world, a, b).map_err(|e| fail(format!("links[{i}]"), e.to_string()))?;
        items.name(link, format!("links[{i}]"));
    }
    if let Some(spec) = scene.spaghetti_factory {
        world.spawn(SpaghettiFactory::new(spec));
    }
    if let Some(spec) = scene.meatball_factory {
        world.spawn(MeatballFactory::new(spec));
    }
    if let Some(spec) = scene.drain {
        world.spawn(Drain::new(spec));
    }
    if let Some(spec) = scene.furry_creature {
        spawn_furry_creature(world, spec);
    }
    for (i, particle) in scene.particles.iter().enumerate() {
        let mut entity = world.spawn((
            Particle,
            Position(vec2(particle.position)),
            Velocity(vec2(particle.velocity)),
            Mass(particle.mass),
        ));
        if particle.pinned {
            entity.insert(Pinned);
        } else if particle.kinematic {
            entity.insert(Kinematic);
        }
        let id = entity.id();
        items.name(id, format!("particles[{i}]"));
    }
    world.insert_resource(items);
    check_initial_state(world, scene)
}

/// The walls of an axis-aligned box: a closed loop of four pinned particles, with no
/// springs or bending (its edges are static obstacles).
pub fn container_builder(min: DVec2, max: DVec2) -> StrandBuilder {
    let corners = [min, DVec2::new(max.x, min.y), max, DVec2::new(min.x, max.y)];
    let mut builder = StrandBuilder::closed_loop(corners)
        .kind(StrandKind::Wall)
        .material(StrandMaterial::INERT);
    for i in 0..4 {
        builder = builder.pin(i);
    }
    builder
}
