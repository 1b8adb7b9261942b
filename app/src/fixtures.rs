//! Set-up shared by the repository's tests and benchmarks: a headless app driven by
//! hand, ticks, the unit box, checked crossings, and the Collide stage run on its own.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::collision::plugin::{account_collisions, impulses, proximity};
use bevy_strands::contact::plugin::contact_loop;
use bevy_strands::prelude::*;

use crate::scenes::ScenesPlugin;
use crate::spawn::container_builder;

/// A headless app on `MinimalPlugins` with the simulation driven by hand.
pub fn app() -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StrandsPlugin::manual(), ScenesPlugin));
    app.finish();
    app.cleanup();
    app
}

/// A headless app with the crossing check on.
pub fn checked_app() -> App {
    let mut app = app();
    check_crossings(&mut app);
    app
}

/// Turn the crossing check on, counting from now.
pub fn check_crossings(app: &mut App) {
    app.world_mut()
        .resource_mut::<CollisionConfig>()
        .check_crossings = true;
    app.world_mut()
        .resource_mut::<StrandMetrics>()
        .edge_crossings = Some(0);
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
    app.world().get::<Position>(entity).expect("a particle").0
}

/// The velocity of a particle entity.
pub fn velocity(app: &App, entity: Entity) -> DVec2 {
    app.world().get::<Velocity>(entity).expect("a particle").0
}

/// How many times the speed a free fall from height `start` down to `height` allows
/// (under 9.81 m/s²) a body moving at `speed` goes: above one, something gave it
/// energy. The fall counts as at least 1 mm, so a body still at its start reads its
/// speed against that, not a division by zero.
pub fn speed_over_fall(speed: f64, start: f64, height: f64) -> f64 {
    speed / (2.0 * 9.81 * (start - height).max(1e-3)).sqrt()
}

/// The particles of a strand, in order.
pub fn strand_particles(app: &App, strand: Entity) -> Vec<Entity> {
    app.world()
        .get::<Strand>(strand)
        .expect("a strand")
        .particles
        .clone()
}

/// Positions and velocities of a strand's particles.
pub fn strand_state(app: &App, strand: Entity) -> Vec<(DVec2, DVec2)> {
    strand_particles(app, strand)
        .into_iter()
        .map(|p| (position(app, p), velocity(app, p)))
        .collect()
}

/// Step ends at which edges crossed, so far (the crossing check must be on).
pub fn crossings(app: &App) -> u64 {
    app.world()
        .resource::<StrandMetrics>()
        .edge_crossings
        .expect("the crossing check is on")
}

/// The unit box as a pinned closed loop.
pub fn spawn_box(app: &mut App) {
    spawn_container(app.world_mut(), DVec2::ZERO, DVec2::ONE);
}

/// The box from `min` to `max` as a pinned closed loop.
pub fn spawn_container(world: &mut World, min: DVec2, max: DVec2) {
    container_builder(min, max)
        .spawn_in(world)
        .expect("a box with positive sides");
}

/// Run the Collide stage alone, its sub-stages in the order of
/// [`CollideSet`](bevy_strands::schedule::CollideSet), on the packed state as it is.
pub fn run_collide_stage(world: &mut World) {
    world
        .run_system_cached(proximity)
        .expect("the proximity sub-stage runs");
    world
        .run_system_cached(impulses)
        .expect("the impulses sub-stage runs");
    world
        .run_system_cached(contact_loop)
        .expect("the contact loop runs");
    world
        .run_system_cached(account_collisions)
        .expect("the account sub-stage runs");
}
