//! The furry creature's hairs collide with its body: limp hairs that fall over the body
//! drape on its collision outline (and never cross it), where without the outline they
//! fall through the body. And at the scene's game step the roots keep their place and
//! orientation on the moving body.

use bevy::math::DVec2;
use bevy_strands::prelude::*;
use bevy_strands_app::builtin::builtin;
use bevy_strands_app::fixtures::{checked_app, crossings, position, set_step, tick, ticks};
use bevy_strands_app::runner::headless_app;
use bevy_strands_app::scenes::furry_creature::{
    FurryCreature, FurryCreatureSpec, spawn_furry_creature,
};

const BODY_RADIUS: f64 = 0.1;
const INSET: f64 = 0.003;

/// A still creature with 24 limp hairs (no bending stiffness) after 1.5 s: the
/// distance from the body's centre of the free hair particle nearest it, the largest
/// relative length error and the crossed step ends.
fn limp_creature(body_inset: Option<f64>) -> (f64, f64, u64) {
    let mut app = checked_app();
    set_step(&mut app, 1.0 / 300.0, 1);
    {
        let world = app.world_mut();
        let mut collisions = world.resource_mut::<CollisionConfig>();
        collisions.enabled = true;
        collisions.thickness = 0.001;
        world
            .resource_mut::<StrandsConfig>()
            .material
            .bending_stiffness = 0.0;
    }
    let spec = FurryCreatureSpec {
        centre: DVec2::new(0.5, 0.5),
        path_radius: 0.0,
        period: 4.0,
        body_radius: BODY_RADIUS,
        hairs: 24,
        particles_per_hair: 12,
        spacing: 0.01,
        mass: 1.0,
        body_inset,
    };
    spawn_furry_creature(app.world_mut(), spec);
    ticks(&mut app, 450);
    let world = app.world_mut();
    let mut particles = world.query::<(&Position, Option<&Pinned>)>();
    let nearest = (particles.iter(world))
        .filter(|(_, pinned)| pinned.is_none())
        .map(|(p, _)| p.0.distance(spec.centre))
        .fold(f64::INFINITY, f64::min);
    let error = world.resource::<StrandMetrics>().max_rel_length_error;
    (nearest, error, crossings(&app))
}

#[test]
fn limp_hairs_drape_on_the_body_and_never_cross_its_outline() {
    let (nearest, error, crossed) = limp_creature(Some(INSET));
    // The outline's sides touch the circle of radius BODY_RADIUS − INSET: no free
    // particle gets inside it.
    assert!(nearest > BODY_RADIUS - INSET, "{nearest}");
    // The hairs did fall onto the body: they rest within a few thicknesses of it.
    assert!(nearest < BODY_RADIUS, "{nearest}");
    assert_eq!(crossed, 0);
    assert!(error < 1e-12, "{error:e}");
}

#[test]
fn without_a_body_outline_limp_hairs_fall_through_the_body() {
    let (nearest, error, _) = limp_creature(None);
    // Well inside where the outline would have stopped them.
    assert!(nearest < BODY_RADIUS - 5.0 * INSET, "{nearest}");
    assert!(error < 1e-12, "{error:e}");
}

#[test]
fn at_a_game_step_each_root_and_first_edge_ride_the_moving_body_exactly() {
    let scenario = (builtin("furry_creature").expect("a built-in scene"))
        .scenario()
        .expect("it parses");
    assert_eq!(scenario.step.dt, 1.0 / 60.0);
    let mut app = headless_app(&scenario).expect("the scene spawns");
    // A quarter turn of the body in 1/60 s steps, hairs swinging and landing.
    for _ in 0..60 {
        tick(&mut app);
        let time = app.world().resource::<SimulationClock>().time;
        let world = app.world_mut();
        let mut creatures = world.query::<&FurryCreature>();
        let creature = creatures.single(world).expect("one creature").clone();
        let centre = creature.spec.body_centre(time);
        // Two driven particles per hair, then the outline's.
        assert!(creature.roots.len() > 2 * 400, "{}", creature.roots.len());
        for &(particle, offset) in &creature.roots {
            let at = position(&app, particle);
            // Where the body puts it, to round-off: the root's place, and with the
            // second particle the first edge's direction.
            assert!(
                at.distance(centre + offset) < 1e-12,
                "{particle:?} at {at} off {} at t = {time}",
                centre + offset
            );
        }
    }
    let metrics = app.world().resource::<StrandMetrics>();
    assert!(metrics.max_rel_length_error < 1e-12);
}
