//! Shared set-up for the headless integration tests.
#![allow(dead_code)]

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::scene::container_builder;

/// A headless app on `MinimalPlugins`, ticked by hand, with no gravity-independent
/// defaults changed.
pub fn app() -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StrandsPlugin::manual()));
    app.finish();
    app.cleanup();
    app
}

/// Configure the step.
pub fn set_step(app: &mut App, dt: f64, substeps: u32) {
    let mut config = app.world_mut().resource_mut::<StrandsConfig>();
    config.dt = dt;
    config.substeps = substeps;
}

/// Run one tick.
pub fn tick(app: &mut App) {
    app.world_mut().run_schedule(StrandsTick);
}

/// Run `n` ticks.
pub fn ticks(app: &mut App, n: usize) {
    for _ in 0..n {
        tick(app);
    }
}

/// The position of a particle entity.
pub fn position(app: &App, entity: Entity) -> DVec2 {
    app.world().get::<Position>(entity).unwrap().0
}

/// The velocity of a particle entity.
pub fn velocity(app: &App, entity: Entity) -> DVec2 {
    app.world().get::<Velocity>(entity).unwrap().0
}

/// The particles of a strand, in order.
pub fn strand_particles(app: &App, strand: Entity) -> Vec<Entity> {
    app.world().get::<Strand>(strand).unwrap().particles.clone()
}

/// Positions and velocities of a strand's particles.
pub fn strand_state(app: &App, strand: Entity) -> Vec<(DVec2, DVec2)> {
    strand_particles(app, strand)
        .into_iter()
        .map(|p| (position(app, p), velocity(app, p)))
        .collect()
}

/// An app with crossing checks on.
pub fn checked_app() -> App {
    let mut app = app();
    app.world_mut()
        .resource_mut::<CollisionConfig>()
        .check_crossings = true;
    app.world_mut()
        .resource_mut::<StrandMetrics>()
        .edge_crossings = Some(0);
    app
}

/// Step ends at which edges crossed, so far.
pub fn crossings(app: &App) -> u64 {
    app.world()
        .resource::<StrandMetrics>()
        .edge_crossings
        .unwrap()
}

/// The unit box as a pinned closed loop.
pub fn spawn_box(app: &mut App) {
    container_builder(DVec2::ZERO, DVec2::ONE)
        .spawn_in(app.world_mut())
        .unwrap();
}
