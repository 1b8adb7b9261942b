//! Sleeping and waking: a settled pile sleeps and holds exactly still, a run is the
//! same as without sleeping until the first group sleeps, and a sleeping strand wakes
//! when something moving reaches it (and only then), when it is written to, or when its
//! anchor moves.

use bevy::math::DVec2;
use bevy::platform::collections::HashSet;
use bevy::prelude::*;
use bevy_strands::contact_events::TouchingPairs;
use bevy_strands::model::geometry::segment_distance;
use bevy_strands::prelude::*;
use bevy_strands::sleeping::reach::quad_distance;
use bevy_strands_app::fixtures::{
    check_crossings, crossings, position, spawn_box, tick, ticks, velocity,
};
use bevy_strands_app::runner::{RunOptions, headless_app, load_scenario};

/// The built-in pile's bottom 45 strands (675 particles), three steps of 1/300 s a
/// tick, the crossing check on.
fn pile(sleep: bool) -> App {
    let mut scenario = load_scenario(&RunOptions {
        scenario: "pile".into(),
        strands: Some(45),
        ..Default::default()
    })
    .unwrap();
    scenario.step.sleep.enabled = sleep;
    let mut app = headless_app(&scenario).unwrap();
    check_crossings(&mut app);
    app
}

/// The strands (not walls) all of whose free (not pinned, not kinematic) particles
/// sleep, and those with one awake.
fn strands_by_sleep(app: &mut App) -> (HashSet<Entity>, HashSet<Entity>) {
    let world = app.world_mut();
    let mut query = world.query::<(&StrandOf, Has<Sleeping>, Has<Pinned>, Has<Kinematic>)>();
    let (mut asleep, mut awake) = (HashSet::new(), HashSet::new());
    for (owner, sleeping, pinned, kinematic) in query.iter(world) {
        if !(pinned || kinematic) {
            if sleeping {
                asleep.insert(owner.0);
            } else {
                awake.insert(owner.0);
            }
        }
    }
    asleep.retain(|s| !awake.contains(s));
    (asleep, awake)
}

/// Tick until every strand of the pile sleeps (at most `limit` ticks).
fn until_asleep(app: &mut App, limit: usize) {
    for _ in 0..limit {
        tick(app);
        if strands_by_sleep(app).1.is_empty() {
            return;
        }
    }
    let metrics = app.world().resource::<StrandMetrics>();
    panic!(
        "the pile did not fall asleep: {} of {} particles",
        metrics.asleep_particles, metrics.particles
    );
}

#[test]
fn a_settled_pile_sleeps_and_holds_exactly_still() {
    let mut app = pile(true);
    until_asleep(&mut app, 600);
    let before = app.world().resource::<ParticleState>().clone();
    let metrics = app.world().resource::<StrandMetrics>().clone();
    assert_eq!(metrics.asleep_particles, 45 * 15);
    ticks(&mut app, 100);
    let after = app.world().resource::<ParticleState>();
    assert_eq!(before.position, after.position, "asleep, nothing moves");
    assert!(after.velocity.iter().all(|v| *v == DVec2::ZERO));
    let metrics = app.world().resource::<StrandMetrics>();
    assert_eq!(metrics.wakes, 0);
    assert!(metrics.max_rel_length_error < 1e-12);
    assert_eq!(crossings(&app), 0);
}

#[test]
fn until_the_first_group_sleeps_a_run_is_the_same_as_without_sleeping() {
    let (mut sleeping, mut awake) = (pile(true), pile(false));
    let mut compared = 0;
    loop {
        tick(&mut sleeping);
        tick(&mut awake);
        if sleeping.world().resource::<StrandMetrics>().sleeps > 0 {
            break;
        }
        let (a, b) = (
            sleeping.world().resource::<ParticleState>(),
            awake.world().resource::<ParticleState>(),
        );
        assert_eq!(a.position, b.position, "tick {compared}");
        assert_eq!(a.velocity, b.velocity, "tick {compared}");
        compared += 1;
        assert!(compared < 1000, "nothing slept in ten seconds");
    }
    // The pile lands and settles for a good part of a second first.
    assert!(compared > 50, "{compared} ticks");
}

/// A ring of `n` particles of radius `r` at `centre`, falling at `speed`.
fn ball(world: &mut World, centre: DVec2, r: f64, n: usize, speed: f64) -> Entity {
    let points = (0..n).map(|k| {
        let angle = std::f64::consts::TAU * k as f64 / n as f64;
        centre + r * DVec2::new(angle.cos(), angle.sin())
    });
    StrandBuilder::closed_loop(points)
        .velocity(DVec2::new(0.0, -speed))
        .rest_shape_from_points()
        .spawn_in(world)
        .unwrap()
}

/// The edges of every strand, as pairs of positions, by strand.
fn strand_segments(app: &mut App, strand: Entity) -> Vec<(DVec2, DVec2)> {
    let world = app.world_mut();
    let strand = world.get::<Strand>(strand).unwrap().clone();
    let at = |e: Entity| world.get::<Position>(e).unwrap().0;
    let n = strand.particles.len();
    let edges = if strand.closed { n } else { n - 1 };
    (0..edges)
        .map(|k| (at(strand.particles[k]), at(strand.particles[(k + 1) % n])))
        .collect()
}

#[test]
fn a_ball_dropped_on_a_sleeping_pile_wakes_the_strands_it_reaches() {
    let mut app = pile(true);
    until_asleep(&mut app, 600);
    let (asleep, _) = strands_by_sleep(&mut app);
    // Over the middle of the pile, just above its top.
    let top = app
        .world()
        .resource::<ParticleState>()
        .position
        .iter()
        .zip(&app.world().resource::<ParticleState>().inverse_mass)
        .filter(|(p, _)| p.x > 0.4 && p.x < 0.6)
        .map(|(p, _)| p.y)
        .fold(f64::NEG_INFINITY, f64::max);
    let (r, speed) = (0.03, 0.5);
    let centre = DVec2::new(0.5, top + r + 0.03);
    let ball = ball(app.world_mut(), centre, r, 12, speed);

    let thickness = app.world().resource::<CollisionConfig>().thickness;
    let tick_seconds = app.world().resource::<StrandsConfig>().tick_seconds();
    let mut touched = HashSet::new();
    let mut first_woken: Option<HashSet<Entity>> = None;
    for _ in 0..40 {
        // Where the ball will sweep this tick, and which sleeping strands that passes
        // within two thicknesses of (gravity's fall over the tick counted too).
        let ring = app.world().get::<Strand>(ball).map(|s| s.particles.clone());
        let sweeps: Vec<(DVec2, DVec2)> = ring
            .unwrap()
            .iter()
            .map(|&p| {
                let (x, v) = (
                    app.world().get::<Position>(p).unwrap().0,
                    app.world().get::<Velocity>(p).unwrap().0,
                );
                let fall = 0.5 * DVec2::new(0.0, -9.81) * tick_seconds * tick_seconds;
                (x, x + (tick_seconds * v + fall))
            })
            .collect();
        let (before, _) = strands_by_sleep(&mut app);
        let mut reached = HashSet::new();
        for &strand in &before {
            // A ball particle's sweep near an edge, or a ball edge's sweep near a
            // particle.
            let segments = strand_segments(&mut app, strand);
            let near = segments.iter().any(|&(a, b)| {
                sweeps
                    .iter()
                    .any(|&(p, q)| segment_distance(p, q, a, b) <= 2.0 * thickness)
            }) || (segments
                .iter()
                .map(|s| s.0)
                .chain(segments.last().map(|s| s.1)))
            .any(|a| {
                (0..sweeps.len()).any(|k| {
                    let ((p0, p1), (q0, q1)) = (sweeps[k], sweeps[(k + 1) % sweeps.len()]);
                    quad_distance(a, [p0, q0, q1, p1]) <= 2.0 * thickness
                })
            });
            if near {
                reached.insert(strand);
            }
        }
        tick(&mut app);
        let (now, _) = strands_by_sleep(&mut app);
        let woken: HashSet<Entity> = before.difference(&now).copied().collect();
        if first_woken.is_none() && !woken.is_empty() {
            // The first strands to wake are exactly those the ball's sweep reached.
            assert_eq!(woken, reached, "woken against reached");
            first_woken = Some(woken);
        }
        let pairs = app.world().resource::<TouchingPairs>();
        for &(a, b) in &pairs.previous {
            if a == ball || b == ball {
                touched.insert(if a == ball { b } else { a });
            }
        }
    }
    let first = first_woken.expect("the ball woke something");
    let (still_asleep, awake) = strands_by_sleep(&mut app);
    // Every strand the ball touched is awake; most of the pile sleeps on.
    touched.retain(|s| asleep.contains(s));
    assert!(!touched.is_empty());
    assert!(
        touched.iter().all(|s| awake.contains(s)),
        "touched {touched:?}"
    );
    assert!(
        still_asleep.len() * 2 > asleep.len(),
        "{} of {} still asleep, first woken {}",
        still_asleep.len(),
        asleep.len(),
        first.len()
    );
    let metrics = app.world().resource::<StrandMetrics>();
    assert!(metrics.max_rel_length_error < 1e-12);
    assert_eq!(crossings(&app), 0);
}

#[test]
fn writing_to_a_sleeping_particle_wakes_its_strand_alone() {
    let mut app = pile(true);
    until_asleep(&mut app, 600);
    let (asleep, _) = strands_by_sleep(&mut app);
    let strand = *asleep.iter().next().unwrap();
    let particle = app.world().get::<Strand>(strand).unwrap().particles[3];
    app.world_mut().get_mut::<Velocity>(particle).unwrap().0 = DVec2::new(0.0, 0.02);
    tick(&mut app);
    let (_, awake) = strands_by_sleep(&mut app);
    assert_eq!(awake, HashSet::from([strand]));
}

#[test]
fn a_rope_sleeps_on_its_anchor_and_wakes_when_the_anchor_moves() {
    let mut app = bevy_strands_app::fixtures::app();
    let hook = app
        .world_mut()
        .spawn(GlobalTransform::from_translation(Vec3::new(0.0, 1.0, 0.0)))
        .id();
    let rope = StrandBuilder::line(DVec2::new(0.0, 1.0), DVec2::new(0.0, -1.0), 10, 0.05)
        .spawn_in(app.world_mut())
        .unwrap();
    let top = app.world().get::<Strand>(rope).unwrap().particles[0];
    app.world_mut().entity_mut(top).insert(Anchor {
        target: hook,
        offset: Vec2::ZERO,
    });
    // Hanging straight down, it rests from the start.
    ticks(&mut app, 120);
    let (asleep, _) = strands_by_sleep(&mut app);
    assert!(asleep.contains(&rope));
    ticks(&mut app, 10);
    assert_eq!(app.world().resource::<StrandMetrics>().wakes, 0);
    *app.world_mut().get_mut::<GlobalTransform>(hook).unwrap() =
        GlobalTransform::from_translation(Vec3::new(0.1, 1.0, 0.0));
    tick(&mut app);
    let (_, awake) = strands_by_sleep(&mut app);
    assert!(awake.contains(&rope));
    ticks(&mut app, 30);
    let end = app.world().get::<Position>(top).unwrap().0;
    // The hook is where its f32 transform puts it.
    assert!((end - DVec2::new(0.1, 1.0)).length() < 1e-6, "{end}");
}

#[test]
fn turning_sleeping_off_wakes_everything() {
    let mut app = pile(true);
    until_asleep(&mut app, 600);
    app.world_mut()
        .resource_mut::<StrandsConfig>()
        .sleep
        .enabled = false;
    tick(&mut app);
    let (asleep, awake) = strands_by_sleep(&mut app);
    assert!(asleep.is_empty());
    assert_eq!(awake.len(), 45);
    assert_eq!(app.world().resource::<StrandMetrics>().asleep_particles, 0);
}

#[test]
fn despawning_a_strand_wakes_the_strands_that_rested_on_it() {
    let mut app = pile(true);
    until_asleep(&mut app, 600);
    let (asleep, _) = strands_by_sleep(&mut app);
    // A strand from the middle of the pile: its lowest particle the median height.
    let mut by_height: Vec<(f64, Entity)> = asleep
        .iter()
        .map(|&s| {
            let low = strand_segments(&mut app, s)
                .iter()
                .map(|&(a, _)| a.y)
                .fold(f64::INFINITY, f64::min);
            (low, s)
        })
        .collect();
    by_height.sort_by(|a, b| a.0.total_cmp(&b.0));
    let gone = by_height[by_height.len() / 2].1;
    let lay = strand_segments(&mut app, gone);
    let thickness = app.world().resource::<CollisionConfig>().thickness;
    let near: HashSet<Entity> = asleep
        .iter()
        .copied()
        .filter(|&s| s != gone)
        .filter(|&s| {
            strand_segments(&mut app, s).iter().any(|&(a, b)| {
                lay.iter()
                    .any(|&(p, q)| segment_distance(p, q, a, b) <= 2.0 * thickness)
            })
        })
        .collect();
    assert!(!near.is_empty());
    app.world_mut().despawn(gone);
    tick(&mut app);
    let (_, awake) = strands_by_sleep(&mut app);
    // Exactly the strands within reach of where it lay.
    assert_eq!(awake, near);
    ticks(&mut app, 100);
    let metrics = app.world().resource::<StrandMetrics>();
    assert!(metrics.max_rel_length_error < 1e-12);
    assert_eq!(crossings(&app), 0);
}

/// Sleeping is never a wall: a rope pushed against a sleeping one, touching it at
/// 3 cm/s — below the sleep speed, so nothing counts as moving towards it — wakes it by
/// the touch and pushes it along the floor; the wake stops at what is touched.
#[test]
fn a_strand_creeping_against_a_sleeping_one_wakes_it_and_pushes_it() {
    let mut app = bevy_strands_app::fixtures::checked_app();
    spawn_box(&mut app);
    app.world_mut().resource_mut::<CollisionConfig>().friction = 0.0;
    let lying = |x: f64| StrandBuilder::line(DVec2::new(x, 0.006), DVec2::X, 5, 0.02);
    let world = app.world_mut();
    let pusher = lying(0.2).spawn_in(world).unwrap();
    let pushed = lying(0.285).spawn_in(world).unwrap();
    let beyond = lying(0.05).spawn_in(world).unwrap();
    for _ in 0..300 {
        tick(&mut app);
        if strands_by_sleep(&mut app).1.is_empty() {
            break;
        }
    }
    assert!(
        strands_by_sleep(&mut app).1.is_empty(),
        "the ropes did not sleep"
    );
    let first = |app: &App, s: Entity| app.world().get::<Strand>(s).unwrap().particles[0];
    let start = position(&app, first(&app, pushed));
    for &p in &app.world().get::<Strand>(pusher).unwrap().particles.clone() {
        app.world_mut()
            .entity_mut(p)
            .insert(ExternalForce(DVec2::new(0.5, 0.0)));
    }
    // Until the pushed rope wakes, the pusher is slower than the sleep speed.
    let (mut fastest, mut woke) = (0.0f64, None);
    for k in 0..200 {
        tick(&mut app);
        let particles = app.world().get::<Strand>(pusher).unwrap().particles.clone();
        if woke.is_none() {
            for p in particles {
                fastest = fastest.max(velocity(&app, p).length());
            }
            if !strands_by_sleep(&mut app).0.contains(&pushed) {
                woke = Some(k);
            }
        }
    }
    assert!(woke.is_some(), "the sleeping rope never woke");
    assert!(fastest < 0.05, "the pusher reached {fastest} m/s first");
    let moved = position(&app, first(&app, pushed)) - start;
    assert!(
        moved.x > 0.02,
        "the sleeping rope was a wall: moved {moved}"
    );
    let (asleep, _) = strands_by_sleep(&mut app);
    assert!(asleep.contains(&beyond), "a rope nothing touched was woken");
    let metrics = app.world().resource::<StrandMetrics>();
    assert!(metrics.max_rel_length_error < 1e-12);
    assert_eq!(crossings(&app), 0);
}
