//! Driven by a schedule: the plugin steps by that schedule's delta and leaves the app's
//! clocks alone, and user systems order themselves around the tick.

use std::time::Duration;

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_strands::prelude::*;

/// A game's app: its own fixed rate (50 Hz here, not Bevy's 64 Hz default), frames of
/// 1/60 s, and the plugin in its default schedule.
fn game() -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StrandsPlugin::default()));
    app.insert_resource(Time::<Fixed>::from_hz(50.0));
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
        1.0 / 60.0,
    )));
    app.world_mut().spawn((
        Particle,
        Position(DVec2::new(0.5, 0.9)),
        Velocity(DVec2::ZERO),
    ));
    app
}

#[test]
fn the_fixed_clock_is_the_games_and_the_step_is_its_delta_over_the_substeps() {
    let mut app = game();
    for _ in 0..90 {
        app.update();
    }
    let fixed = app.world().resource::<Time<Fixed>>();
    assert_eq!(fixed.timestep(), Duration::from_millis(20));
    let config = app.world().resource::<StrandsConfig>();
    assert_eq!(config.dt, 0.02 / config.substeps as f64);
    // Every fixed tick of the game took one tick of the simulation.
    let clock = app.world().resource::<SimulationClock>();
    let ticks = (fixed.elapsed_secs_f64() / 0.02).round() as u64;
    assert!(ticks > 60, "{ticks} fixed ticks in 1.5 s");
    assert_eq!(clock.steps, ticks * config.substeps as u64);
    assert!((clock.time - fixed.elapsed_secs_f64()).abs() < 1e-9);

    // Changing the simulation's settings does not touch the game's clock.
    app.world_mut().resource_mut::<StrandsConfig>().substeps = 3;
    app.update();
    app.update();
    assert_eq!(
        app.world().resource::<Time<Fixed>>().timestep(),
        Duration::from_millis(20)
    );
    assert_eq!(app.world().resource::<StrandsConfig>().dt, 0.02 / 3.0);
}

#[test]
fn paused_the_simulation_takes_no_step_while_the_game_runs_on() {
    let mut app = game();
    for _ in 0..10 {
        app.update();
    }
    let steps = app.world().resource::<SimulationClock>().steps;
    assert!(steps > 0);
    app.world_mut().resource_mut::<StrandsConfig>().paused = true;
    for _ in 0..10 {
        app.update();
    }
    assert_eq!(app.world().resource::<SimulationClock>().steps, steps);
    app.world_mut().resource_mut::<StrandsConfig>().paused = false;
    app.update();
    app.update();
    assert!(app.world().resource::<SimulationClock>().steps > steps);
}

#[derive(Resource, Default)]
struct Seen(Vec<(&'static str, u64)>);

#[test]
fn systems_ordered_around_the_tick_see_the_state_before_and_after_it() {
    let mut app = game();
    app.init_resource::<Seen>();
    let record = |label: &'static str| {
        move |clock: Res<SimulationClock>, mut seen: ResMut<Seen>| {
            seen.0.push((label, clock.steps));
        }
    };
    app.add_systems(
        FixedPostUpdate,
        (
            record("before").before(StrandsSystems),
            record("after").after(StrandsSystems),
        ),
    );
    for _ in 0..5 {
        app.update();
    }
    let substeps = app.world().resource::<StrandsConfig>().substeps as u64;
    let seen = &app.world().resource::<Seen>().0;
    assert!(seen.len() >= 4, "{seen:?}");
    for pair in seen.chunks(2) {
        assert_eq!(pair[0].0, "before");
        assert_eq!(pair[1], ("after", pair[0].1 + substeps));
    }
}

#[test]
fn a_synced_particles_transform_follows_its_position() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StrandsPlugin::manual()));
    let start = DVec2::new(0.25, 0.75);
    let p = app
        .world_mut()
        .spawn((
            Particle,
            Position(start),
            Velocity(DVec2::new(1.0, 0.0)),
            SyncTransform { interpolate: false },
            Transform::from_xyz(0.0, 0.0, 3.0),
        ))
        .id();
    // Before any tick: where it was spawned, its z kept.
    app.update();
    let translation = |app: &App| app.world().get::<Transform>(p).unwrap().translation;
    assert_eq!(translation(&app), Vec3::new(0.25, 0.75, 3.0));
    for _ in 0..3 {
        app.world_mut().run_schedule(StrandsTick);
        app.update();
        let x = app.world().get::<Position>(p).unwrap().0;
        assert_eq!(translation(&app), x.as_vec2().extend(3.0));
    }
    // Three ticks of 6 × 1/600 s at 1 m/s.
    assert!((translation(&app).x - 0.28).abs() < 1e-6);
}

#[test]
fn interpolated_transforms_land_between_the_last_two_ticks() {
    let mut app = game();
    let p = app
        .world_mut()
        .spawn((
            Particle,
            Position(DVec2::new(0.5, 0.5)),
            Velocity(DVec2::new(2.0, 0.0)),
            SyncTransform::default(),
        ))
        .id();
    let mut strictly_between = 0;
    for _ in 0..40 {
        app.update();
        if app.world().resource::<SimulationClock>().steps == 0 {
            continue;
        }
        let ticks = *app.world().get::<TickPositions>(p).unwrap();
        let alpha = app
            .world()
            .resource::<Time<Fixed>>()
            .overstep_fraction_f64();
        let x = app.world().get::<Transform>(p).unwrap().translation.x;
        assert_eq!(x, ticks.at(alpha).x as f32);
        if ticks.previous.x < ticks.current.x
            && x > ticks.previous.x as f32
            && x < ticks.current.x as f32
        {
            strictly_between += 1;
        }
    }
    // Frames of 1/60 s against ticks of 1/50 s: most frames fall inside a tick.
    assert!(
        strictly_between > 20,
        "{strictly_between} of 40 frames between ticks"
    );
}

/// A rope that swings down onto a floor, in a world of `unit` world units per metre.
fn rope_world(unit: f64) -> (App, Entity) {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        StrandsPlugin::manual().with_length_unit(unit),
    ));
    let world = app.world_mut();
    StrandBuilder::polyline([DVec2::new(0.0, 0.1), DVec2::new(1.0, 0.1)].map(|p| p * unit))
        .pin(0)
        .pin(1)
        .kind(StrandKind::Wall)
        .material(StrandMaterial::INERT)
        .spawn_in(world)
        .unwrap();
    let rope = StrandBuilder::line(DVec2::new(0.3, 0.4) * unit, DVec2::X, 20, 0.02 * unit)
        .pin_first()
        .spawn_in(world)
        .unwrap();
    (app, rope)
}

#[test]
fn a_pixel_world_with_its_length_unit_moves_as_the_metre_world_scaled() {
    let (mut metres, rope_m) = rope_world(1.0);
    let (mut pixels, rope_px) = rope_world(100.0);
    let unit = pixels.world().resource::<LengthUnit>().0;
    assert_eq!(unit, 100.0);
    assert_eq!(pixels.world().resource::<CollisionConfig>().thickness, 0.4);
    assert_eq!(pixels.world().resource::<StrandsConfig>().gravity.y, -981.0);
    let mut landed = false;
    for _ in 0..120 {
        metres.world_mut().run_schedule(StrandsTick);
        pixels.world_mut().run_schedule(StrandsTick);
        let particles = |app: &App, s: Entity| -> Vec<DVec2> {
            let strand = app.world().get::<Strand>(s).unwrap();
            strand
                .particles
                .iter()
                .map(|&p| app.world().get::<Position>(p).unwrap().0)
                .collect()
        };
        for (m, px) in particles(&metres, rope_m)
            .iter()
            .zip(particles(&pixels, rope_px))
        {
            assert!(m.distance(px / unit) < 1e-9, "{m} against {}", px / unit);
        }
        landed |= metres.world().resource::<StrandMetrics>().contacts > 0;
    }
    assert!(landed, "the rope reached the floor");
    let error = |app: &App| app.world().resource::<StrandMetrics>().max_rel_length_error;
    assert!(error(&metres) < 1e-9 && error(&pixels) < 1e-9);
}

#[test]
fn an_anchored_particle_follows_its_entity_and_the_rope_stays_exact() {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        bevy::transform::TransformPlugin,
        StrandsPlugin::manual(),
    ));
    let crane = app
        .world_mut()
        .spawn(Transform::from_xyz(0.5, 0.8, 0.0))
        .id();
    let rope = StrandBuilder::line(DVec2::new(0.6, 0.8), DVec2::X, 15, 0.02)
        .spawn_in(app.world_mut())
        .unwrap();
    let hook = app.world().get::<Strand>(rope).unwrap().particles[0];
    let offset = Vec2::new(0.1, 0.0);
    app.world_mut().entity_mut(hook).insert(Anchor {
        target: crane,
        offset,
    });
    for k in 0..120 {
        // The crane circles and turns.
        let t = k as f32 / 60.0;
        *app.world_mut().get_mut::<Transform>(crane).unwrap() =
            Transform::from_xyz(0.5 + 0.1 * t.cos(), 0.8 + 0.1 * t.sin(), 0.0)
                .with_rotation(Quat::from_rotation_z(t));
        app.update();
        app.world_mut().run_schedule(StrandsTick);
        let target = app.world().get::<GlobalTransform>(crane).unwrap();
        let point = target
            .transform_point(offset.extend(0.0))
            .truncate()
            .as_dvec2();
        let at = app.world().get::<Position>(hook).unwrap().0;
        assert!(at.distance(point) < 1e-12, "tick {k}: {at} against {point}");
    }
    assert!(app.world().get::<Kinematic>(hook).is_some());
    let error = app.world().resource::<StrandMetrics>().max_rel_length_error;
    assert!(error < 1e-9, "{error:e}");
}
