//! Reliability inside a game: a non-finite value is caught in the stage that made it,
//! its island is frozen at its last finite state, and everything else steps on as if it
//! had not happened.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::guard::Quantity;
use bevy_strands::prelude::*;
use bevy_strands_app::fixtures::*;

/// Two ropes far apart; `poison` gives the first one's third particle a force that
/// overflows once gravity is added to it.
fn two_ropes(poison: bool) -> (App, Entity, Entity) {
    let mut app = app();
    set_step(&mut app, 1.0 / 600.0, 4);
    let world = app.world_mut();
    let bad = StrandBuilder::line(DVec2::new(0.1, 0.9), DVec2::X, 8, 0.02)
        .pin_first()
        .spawn_in(world)
        .unwrap();
    let good = StrandBuilder::line(DVec2::new(0.6, 0.9), DVec2::X, 8, 0.02)
        .pin_first()
        .spawn_in(world)
        .unwrap();
    if poison {
        let third = strand_particles(&app, bad)[2];
        // m g is finite and so is the external force; their sum is not.
        app.world_mut()
            .entity_mut(third)
            .insert((Mass(1e300), ExternalForce(DVec2::new(0.0, -f64::MAX))));
    }
    (app, bad, good)
}

#[test]
fn a_non_finite_force_freezes_its_island_and_nothing_else() {
    let (mut clean, _, clean_good) = two_ropes(false);
    let (mut app, bad, good) = two_ropes(true);
    let start: Vec<DVec2> = strand_particles(&app, bad)
        .iter()
        .map(|&p| position(&app, p))
        .collect();
    ticks(&mut clean, 30);
    ticks(&mut app, 30);

    let events = &app.world().resource::<FiniteGuard>().events;
    assert_eq!(events.len(), 1, "{events:?}");
    let event = &events[0];
    let third = strand_particles(&app, bad)[2];
    assert_eq!((event.step, event.stage), (1, StepSet::Forces));
    assert_eq!((event.particle, event.strand), (third, Some(bad)));
    assert_eq!(event.quantity, Quantity::Force);
    assert_eq!(event.value.y, f64::NEG_INFINITY);
    // Its island: the rope but its pinned first particle, which never moves anyway.
    assert_eq!((event.bad_particles, event.frozen_particles), (1, 7));

    // The poisoned rope is held where the first step started, at rest, and marked.
    for (k, (&p, &x)) in strand_particles(&app, bad).iter().zip(&start).enumerate() {
        assert_eq!(position(&app, p), x);
        assert_eq!(velocity(&app, p), DVec2::ZERO);
        assert_eq!(app.world().get::<Frozen>(p).is_some(), k > 0);
    }
    // The other rope swings exactly as it does in a world without the poison.
    for (&p, &q) in strand_particles(&app, good)
        .iter()
        .zip(&strand_particles(&clean, clean_good))
    {
        assert_eq!(position(&app, p), position(&clean, q));
        assert_eq!(velocity(&app, p), velocity(&clean, q));
        assert!(app.world().get::<Frozen>(p).is_none());
    }
    assert!(position(&app, strand_particles(&app, good)[7]).y < 0.85);

    // The message was written too.
    let messages = app.world().resource::<Messages<NonFiniteState>>();
    assert_eq!(messages.iter_current_update_messages().count(), 1);
}

#[test]
fn a_frozen_island_moves_again_once_the_marker_and_the_cause_are_removed() {
    let (mut app, bad, _) = two_ropes(true);
    ticks(&mut app, 3);
    let particles = strand_particles(&app, bad);
    app.world_mut()
        .entity_mut(particles[2])
        .remove::<ExternalForce>()
        .insert(Mass(1.0));
    for &p in &particles {
        app.world_mut().entity_mut(p).remove::<Frozen>();
    }
    let tip = position(&app, particles[7]);
    ticks(&mut app, 10);
    assert!(position(&app, particles[7]).y < tip.y - 1e-3);
    assert_eq!(app.world().resource::<FiniteGuard>().events.len(), 1);
    // The first particle was pinned before and still is.
    assert_eq!(position(&app, particles[0]), DVec2::new(0.1, 0.9));
}

#[test]
fn a_velocity_that_overflows_in_the_predictor_is_caught_there() {
    let mut app = app();
    set_step(&mut app, 1e300, 1);
    let p = app
        .world_mut()
        .spawn((
            Particle,
            Position(DVec2::new(0.5, 0.5)),
            Velocity(DVec2::ZERO),
        ))
        .id();
    // dt g overflows in the first prediction: v = 1e300 (-9.81).
    app.world_mut().resource_mut::<StrandsConfig>().gravity = DVec2::new(0.0, -1e10);
    ticks(&mut app, 2);
    let events = &app.world().resource::<FiniteGuard>().events;
    assert_eq!(events.len(), 1);
    assert_eq!(
        (events[0].stage, events[0].quantity),
        (StepSet::Predict, Quantity::Velocity)
    );
    assert_eq!(events[0].strand, None);
    assert_eq!(position(&app, p), DVec2::new(0.5, 0.5));
    assert!(app.world().get::<Frozen>(p).is_some());
}

#[test]
fn strands_and_particles_past_the_caps_are_left_out_with_a_message() {
    let mut app = app();
    app.world_mut()
        .resource_mut::<StrandsConfig>()
        .max_particles = 25;
    let world = app.world_mut();
    let strands: Vec<Entity> = (0..3)
        .map(|s| {
            StrandBuilder::line(DVec2::new(0.1, 0.2 + 0.2 * s as f64), DVec2::X, 10, 0.02)
                .spawn_in(world)
                .unwrap()
        })
        .collect();
    let loose: Vec<Entity> = (0..7)
        .map(|i| {
            let x = DVec2::new(0.1 + 0.05 * i as f64, 0.9);
            world
                .spawn((Particle, Position(x), Velocity(DVec2::ZERO)))
                .id()
        })
        .collect();
    ticks(&mut app, 2);
    assert_eq!(app.world().resource::<ParticleState>().len(), 25);
    let simulated =
        |app: &App, p: Entity| app.world().resource::<Topology>().index.contains_key(&p);
    // One strand is left out whole (the last in the topology's entity order).
    let is_in = |app: &App, s: Entity| strand_particles(app, s).iter().all(|&p| simulated(app, p));
    let out: Vec<Entity> = strands
        .iter()
        .copied()
        .filter(|&s| !is_in(&app, s))
        .collect();
    assert_eq!(out.len(), 1);
    let third = strand_particles(&app, out[0]);
    assert!(third.iter().all(|&p| !simulated(&app, p)));
    assert_eq!(loose.iter().filter(|&&p| simulated(&app, p)).count(), 5);
    // Left out, they stay where they were: not loose particles falling on their own.
    let start = position(&app, third[0]);
    tick(&mut app);
    assert_eq!(position(&app, third[0]), start);
    let problems = &app.world().resource::<InputProblems>();
    assert!(problems.entries.iter().any(|p| {
        p.entity == out[0]
            && p.problem
                .starts_with("strand left out: with its 10 particles and 9 edges")
            && p.problem.contains("max_particles 25")
    }));
    assert!(
        problems
            .entries
            .iter()
            .any(|p| p.problem.starts_with("2 loose particles left out"))
    );

    // Raised, everything is in at the next rebuild.
    app.world_mut()
        .resource_mut::<StrandsConfig>()
        .max_particles = 100;
    app.world_mut()
        .resource_mut::<bevy_strands::world::hooks::TopologyDirty>()
        .mark();
    tick(&mut app);
    assert_eq!(app.world().resource::<ParticleState>().len(), 37);
}

#[test]
fn a_builder_asked_for_too_many_particles_refuses_without_building_them() {
    use bevy_strands::model::validate::{MAX_STRAND_PARTICLES, StrandError};
    let builder = StrandBuilder::line(DVec2::ZERO, DVec2::X, usize::MAX, 1e-3);
    assert_eq!(builder.points().len(), MAX_STRAND_PARTICLES + 1);
    assert_eq!(
        builder.validate(),
        Err(StrandError::TooManyParticles {
            max: MAX_STRAND_PARTICLES
        })
    );
}

/// A rope whose pinned end is moved a metre away, farther than the rope reaches: no
/// solve can keep its edges, and the first step that ends with one stretched past
/// `MAX_STRETCH` freezes its island with a message, where it was at that step's start;
/// a rope beside it swings on untouched.
#[test]
fn an_edge_stretched_past_its_bound_freezes_its_island_with_a_message() {
    let (mut app, rope, good) = two_ropes(false);
    let last = *strand_particles(&app, rope).last().unwrap();
    app.world_mut().entity_mut(last).insert(Pinned);
    ticks(&mut app, 2);
    assert!(app.world().resource::<FiniteGuard>().events.is_empty());
    let at = position(&app, last);
    app.world_mut()
        .entity_mut(last)
        .insert(Position(at + DVec2::new(1.0, 0.0)));
    ticks(&mut app, 5);

    let events = &app.world().resource::<FiniteGuard>().events;
    assert_eq!(events.len(), 1, "{events:?}");
    let event = &events[0];
    assert_eq!(event.quantity, Quantity::Stretch);
    assert_eq!(event.stage, StepSet::Measure);
    assert_eq!(event.strand, Some(rope));
    assert!(
        event.value.x > bevy_strands::guard::MAX_STRETCH && event.value.x.is_finite(),
        "{event:?}"
    );
    // Every particle of the rope but its two pins is frozen, and stays where it was.
    let particles = strand_particles(&app, rope);
    for &p in &particles[1..7] {
        assert!(app.world().get::<Frozen>(p).is_some());
    }
    let held: Vec<DVec2> = particles.iter().map(|&p| position(&app, p)).collect();
    ticks(&mut app, 3);
    for (&p, &x) in particles.iter().zip(&held) {
        assert_eq!(position(&app, p), x);
    }
    assert_eq!(app.world().resource::<FiniteGuard>().events.len(), 1);
    // The other rope is untouched and swings.
    for &p in &strand_particles(&app, good) {
        assert!(app.world().get::<Frozen>(p).is_none());
    }
    assert!(position(&app, strand_particles(&app, good)[7]).y < 0.89);
}

/// The particles a rogue stage speeds up.
#[derive(Resource)]
struct Pumped(Vec<Entity>);

/// A stand-in for a solve that puts energy in: each step, after the contacts, it speeds
/// the pumped particles up by a tenth.
fn pump(pumped: Res<Pumped>, mut state: ResMut<ParticleState>) {
    let state = &mut *state;
    for (v, e) in state.velocity.iter_mut().zip(&state.entity) {
        if pumped.0.contains(e) {
            *v *= 1.1;
        }
    }
}

/// Energy from nowhere is caught though every value is finite and every edge exact: a
/// rope swinging ever faster is frozen with a `Speed` message well before it goes
/// twice as fast as its fall allows, and the rope beside it swings on.
#[test]
fn kinetic_energy_no_force_explains_freezes_its_island_with_a_message() {
    let (mut app, rope, good) = two_ropes(false);
    let pumped = strand_particles(&app, rope);
    app.insert_resource(Pumped(pumped.clone()));
    app.add_systems(
        StrandsStep,
        pump.in_set(StepSet::Collide).after(CollideSet::Account),
    );
    // Horizontal, 0.14 m long, pinned at one end: no particle can pass sqrt(2 g 0.14).
    let explained = (2.0 * 9.81 * 0.14f64).sqrt();
    let mut fastest: f64 = 0.0;
    for _ in 0..120 {
        tick(&mut app);
        if !app.world().resource::<FiniteGuard>().events.is_empty() {
            break;
        }
        for &p in &pumped {
            fastest = fastest.max(velocity(&app, p).length());
        }
    }
    let events = &app.world().resource::<FiniteGuard>().events;
    assert_eq!(events.len(), 1, "{events:?}");
    let event = &events[0];
    assert_eq!(event.quantity, Quantity::Speed);
    assert_eq!(event.strand, Some(rope));
    assert!(
        event.value.is_finite() && event.value.length() > explained,
        "{event:?}"
    );
    assert!(
        fastest < 2.0 * explained,
        "{fastest} m/s before the guard acted"
    );
    for &p in &pumped[1..] {
        assert!(app.world().get::<Frozen>(p).is_some());
        assert_eq!(velocity(&app, p), DVec2::ZERO);
    }
    for &p in &strand_particles(&app, good) {
        assert!(app.world().get::<Frozen>(p).is_none());
    }
    // Frozen, the pump has nothing left to speed up: no second message.
    ticks(&mut app, 30);
    assert_eq!(app.world().resource::<FiniteGuard>().events.len(), 1);
}

/// How a test drives its one rope.
#[derive(Clone, Copy, Debug)]
enum Driver {
    /// An external force on every particle, its pin let go.
    Pushed,
    /// Its end kinematic, driven round a circle by its velocity.
    Kinematic,
    /// Its end pinned, carried round the circle by writing its position.
    Carried,
}

/// What a scene's own forces and drivers put in is explained: a free rope pushed by an
/// external force to tens of metres a second, one whose end is driven round a circle
/// and one whose pinned end is carried round it (written every tick) run without a
/// message, at a game's step and a fine one, each alone (the account is the scene's).
#[test]
fn energy_put_in_by_forces_and_drivers_is_explained() {
    for driver in [Driver::Pushed, Driver::Kinematic, Driver::Carried] {
        for (dt, substeps) in [(1.0 / 60.0, 1), (1.0 / 600.0, 4)] {
            let mut app = app();
            set_step(&mut app, dt, substeps);
            let rope = StrandBuilder::line(DVec2::new(0.1, 0.9), DVec2::X, 8, 0.02)
                .pin_first()
                .spawn_in(app.world_mut())
                .unwrap();
            let particles = strand_particles(&app, rope);
            let end = particles[0];
            match driver {
                Driver::Pushed => {
                    for &p in &particles {
                        let force = ExternalForce(DVec2::new(-40.0, 10.0));
                        app.world_mut().entity_mut(p).insert(force);
                    }
                    app.world_mut().entity_mut(end).remove::<Pinned>();
                }
                Driver::Kinematic => {
                    app.world_mut()
                        .entity_mut(end)
                        .remove::<Pinned>()
                        .insert(Kinematic);
                }
                Driver::Carried => {}
            }
            let centre = position(&app, end);
            let (tick_seconds, mut fastest) = (dt * f64::from(substeps), 0.0f64);
            for k in 0..240 {
                // Round a 10 cm circle three times a second.
                let w = 6.0 * std::f64::consts::PI;
                let t = k as f64 * tick_seconds;
                let at = centre + 0.1 * DVec2::new((w * t).cos() - 1.0, (w * t).sin());
                let v = 0.1 * w * DVec2::new(-(w * t).sin(), (w * t).cos());
                match driver {
                    Driver::Pushed => {}
                    Driver::Kinematic => {
                        app.world_mut().entity_mut(end).insert(Velocity(v));
                    }
                    Driver::Carried => {
                        app.world_mut().entity_mut(end).insert(Position(at));
                    }
                }
                tick(&mut app);
                for &p in &particles[1..] {
                    fastest = fastest.max(velocity(&app, p).length());
                }
            }
            let events = &app.world().resource::<FiniteGuard>().events;
            assert!(events.is_empty(), "{driver:?} at {dt}: {events:?}");
            // Each drove the rope far past what its fall explains (1.7 m/s).
            assert!(fastest > 4.0, "{driver:?} at {dt}: {fastest} m/s");
        }
    }
}
