//! Shared set-up for the headless integration tests.
#![allow(dead_code)]

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;

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
