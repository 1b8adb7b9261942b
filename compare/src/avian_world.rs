//! The chains in avian2d: capsule links joined end to end by distance joints of rest
//! length zero at the link ends, collisions between joined links off, the container
//! as static rectangles. Avian's defaults otherwise (6 substeps), on Bevy's task pool
//! (one thread per core), stepped by the fixed clock once per `app.update()`.

use std::time::{Duration, Instant};

use avian2d::prelude::*;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;

use crate::chain::Chains;
use crate::rapier_world::walls;
use crate::report::EngineRun;

/// `length_unit` is avian's scale of contact tolerances and speculative margins (1 m
/// by default).
pub fn run(chains: &Chains, dt: f32, steps: u64, length_unit: f32) -> EngineRun {
    let mut app = App::new();
    let physics = PhysicsPlugins::default().with_length_unit(length_unit);
    app.add_plugins((MinimalPlugins, TransformPlugin, physics))
        .insert_resource(Gravity(Vec2::new(0.0, -9.81)))
        .insert_resource(Time::<Fixed>::from_duration(Duration::from_secs_f32(dt)))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
            dt,
        )));
    app.finish();
    app.cleanup();
    let world = app.world_mut();
    for (x, y, hx, hy) in walls(chains.container) {
        world.spawn((
            RigidBody::Static,
            Collider::rectangle(2.0 * hx, 2.0 * hy),
            Friction::new(chains.friction),
            Transform::from_xyz(x, y, 0.0),
        ));
    }
    let r = chains.radius;
    let mut links: Vec<Vec<(Entity, f32)>> = Vec::new();
    for strand in &chains.strands {
        let mut chain = Vec::new();
        for pair in strand.windows(2) {
            let (a, b) = (Vec2::from(pair[0]), Vec2::from(pair[1]));
            let length = (b - a).length();
            let half = Vec2::new(0.5 * length, 0.0);
            // The density that gives the link its share of the strand's mass.
            let area = 2.0 * r * length + std::f32::consts::PI * r * r;
            let centre = 0.5 * (a + b);
            let entity = world
                .spawn((
                    RigidBody::Dynamic,
                    Collider::capsule_endpoints(r, -half, half),
                    ColliderDensity(chains.link_mass / area),
                    Friction::new(chains.friction),
                    Transform::from_xyz(centre.x, centre.y, 0.0)
                        .with_rotation(Quat::from_rotation_z((b - a).to_angle())),
                ))
                .id();
            chain.push((entity, length));
        }
        for pair in chain.windows(2) {
            world.spawn((
                DistanceJoint::new(pair[0].0, pair[1].0)
                    .with_local_anchor1(Vec2::new(0.5 * pair[0].1, 0.0))
                    .with_local_anchor2(Vec2::new(-0.5 * pair[1].1, 0.0)),
                JointCollisionDisabled,
            ));
        }
        links.push(chain);
    }
    let threads = bevy::tasks::ComputeTaskPool::get_or_init(Default::default).thread_num();
    let mut run = EngineRun::new(
        "avian2d",
        "distance joints, capsule links",
        length_unit,
        threads,
    );
    let lengths: Vec<Vec<f32>> = (links.iter())
        .map(|chain| chain.iter().map(|l| l.1).collect())
        .collect();
    // The first update spawns avian's internal state; the clock starts after it.
    app.update();
    run.drive(chains, &lengths, steps, |segments| {
        let began = Instant::now();
        app.update();
        let wall = began.elapsed().as_secs_f64();
        let world = app.world();
        segments.extend(links.iter().map(|chain| {
            chain
                .iter()
                .map(|&(entity, length)| {
                    let position = world.get::<Position>(entity).expect("a link").0;
                    let rotation = *world.get::<Rotation>(entity).expect("a link");
                    let half = rotation * Vec2::new(0.5 * length, 0.0);
                    let (a, b) = (position - half, position + half);
                    [[a.x, a.y], [b.x, b.y]]
                })
                .collect()
        }));
        wall
    });
    run
}
