//! The initial state of a spawned scene, checked before it runs: no two edges cross,
//! no particle lies closer than the thickness to an edge it is not an end of, and every
//! particle is inside the container, a thickness clear of its walls. A scene that
//! breaks one is refused with the items named, unless it says why it starts that way
//! (`allow_initial_contact`).

use bevy::ecs::entity::EntityHashMap;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::collision::broad_phase::BroadPhase;
use bevy_strands::collision::clearance::overlaps;
use bevy_strands::collision::crossings::{Among, count_crossings};
use bevy_strands::prelude::*;
use bevy_strands::schedule::synchronise;

use crate::scenario::{Scenario, ScenarioError};

/// What each spawned strand and loose particle is called in its scene file.
#[derive(Resource, Default, Debug)]
pub struct SceneItems(EntityHashMap<String>);

impl SceneItems {
    /// Call `entity` `name`.
    pub fn name(&mut self, entity: Entity, name: impl Into<String>) {
        self.0.insert(entity, name.into());
    }

    /// The name of a particle: its strand's item and its place along it, or its own.
    pub fn particle(&self, world: &World, particle: Entity) -> String {
        let place = world.get::<StrandOf>(particle).and_then(|of| {
            let index =
                (world.get::<Strand>(of.0)?.particles.iter()).position(|&p| p == particle)?;
            Some(format!("{} particle {index}", self.strand(of.0)))
        });
        place.unwrap_or_else(|| self.strand(particle))
    }

    fn strand(&self, entity: Entity) -> String {
        self.0
            .get(&entity)
            .cloned()
            .unwrap_or_else(|| format!("entity {entity}"))
    }
}

/// Refuse the spawned scene if it starts crossed, overlapping or outside its container.
pub fn check_initial_state(world: &mut World, scene: &Scenario) -> Result<(), ScenarioError> {
    if scene.allow_initial_contact.is_some() {
        return Ok(());
    }
    synchronise(world);
    let problem = first_problem(world, scene);
    problem.map_or(Ok(()), |(item, problem)| {
        Err(ScenarioError::new(scene.origin(), item, problem))
    })
}

fn first_problem(world: &World, scene: &Scenario) -> Option<(String, String)> {
    let items = world.get_resource::<SceneItems>()?;
    let topology = world.resource::<Topology>();
    let state = world.resource::<ParticleState>();
    let config = world.resource::<CollisionConfig>();
    let threads = world.resource::<StrandsConfig>().worker_threads();
    let name = |i: u32| items.particle(world, state.entity[i as usize]);
    let edge_name = |k: u32| {
        let e = &topology.edges[k as usize];
        format!("the edge from {} to {}", name(e.a), name(e.b))
    };
    let advice = "move them apart, or give allow_initial_contact: Some(\"why\")";

    let mut broad = BroadPhase::default();
    let crossings = count_crossings(
        &topology.edges,
        &state.position,
        &mut broad,
        None,
        Among::All,
        config.broad_phase,
        threads,
        &mut Vec::new(),
    );
    if let Some((j, k)) = crossings.first {
        return Some((
            "initial state".into(),
            format!(
                "{} crosses {} (pairs of edges crossing at the start: {}); {advice}",
                edge_name(j),
                edge_name(k),
                crossings.pairs
            ),
        ));
    }

    let h = config.thickness;
    if config.enabled {
        let found = overlaps(
            &topology.edges,
            &state.position,
            &state.inverse_mass,
            h,
            &mut broad,
            config.broad_phase,
            threads,
        );
        if let Some(first) = found.first() {
            return Some((
                "initial state".into(),
                format!(
                    "{} is {:e} from {}, closer than the thickness {h:e} (pairs that \
                     close: {}); {advice}",
                    name(first.point),
                    first.distance,
                    edge_name(first.edge),
                    found.len()
                ),
            ));
        }
    }

    let container = scene.scale.map(|s| s.container()).or(scene.container)?;
    let (min, max) = (DVec2::from(container.min), DVec2::from(container.max));
    let walls = topology
        .strands
        .iter()
        .filter(|r| r.kind == StrandKind::Wall);
    let wall_particles: Vec<u32> = walls
        .flat_map(|r| {
            topology.edges[r.edges.clone()]
                .iter()
                .flat_map(|e| [e.a, e.b])
        })
        .collect();
    let outside = (0..state.len() as u32).find(|&i| {
        let x = state.position[i as usize];
        let inside = x.cmpgt(min + h).all() && x.cmplt(max - h).all();
        !inside && !wall_particles.contains(&i)
    })?;
    Some((
        "initial state".into(),
        format!(
            "{} at {:?} is not inside the container ({:?} to {:?}) by the thickness \
             {h:e}; move it in, or give allow_initial_contact: Some(\"why\")",
            name(outside),
            state.position[outside as usize],
            container.min,
            container.max
        ),
    ))
}
