//! A step taken again: what [`HalvingSaves`] saves before a step is put back exactly,
//! so a step that would end in the fail-safe and is taken as two halves starts the
//! halves from where the step started.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::halving::HalvingSaves;
use bevy_strands::prelude::*;
use bevy_strands::schedule::StrandsStep;

#[test]
fn a_step_put_back_leaves_the_state_as_it_was() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StrandsPlugin::manual()));
    {
        let mut config = app.world_mut().resource_mut::<StrandsConfig>();
        config.dt = 1.0 / 60.0;
        config.substeps = 1;
    }
    StrandBuilder::line(DVec2::new(0.0, 1.0), DVec2::X, 12, 0.05)
        .pin_first()
        .spawn_in(app.world_mut())
        .unwrap();
    app.finish();
    app.cleanup();
    // Two ticks in: the strand swings, the metrics and clock have counts.
    for _ in 0..2 {
        app.world_mut()
            .run_schedule(bevy_strands::schedule::StrandsTick);
    }
    let world = app.world_mut();
    let before = (
        world.resource::<ParticleState>().position.clone(),
        world.resource::<ParticleState>().velocity.clone(),
        world.resource::<StrandMetrics>().clone(),
        *world.resource::<SimulationClock>(),
    );
    world.resource_scope(|world, mut saves: Mut<HalvingSaves>| saves.save(world));
    world.run_schedule(StrandsStep);
    assert_ne!(world.resource::<ParticleState>().position, before.0);
    world.resource_scope(|world, saves: Mut<HalvingSaves>| saves.restore(world));
    let after = (
        world.resource::<ParticleState>().position.clone(),
        world.resource::<ParticleState>().velocity.clone(),
        world.resource::<StrandMetrics>().clone(),
        *world.resource::<SimulationClock>(),
    );
    assert_eq!(after, before);
}
