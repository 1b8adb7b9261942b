//! The chains in rapier2d: capsule links joined end to end by revolute impulse joints,
//! contacts between a link and its joint neighbours off, the container as fixed
//! cuboids. Rapier's defaults otherwise (4 solver iterations), one thread.

use std::time::Instant;

use rapier2d::prelude::*;

use crate::chain::Chains;
use crate::report::EngineRun;

/// `length_unit` is Rapier's scale of contact tolerances (1 m by default; its guide
/// sets it to the size of a typical object).
pub fn run(chains: &Chains, dt: f32, steps: u64, length_unit: f32) -> EngineRun {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = dt;
    world.integration_parameters.length_unit = length_unit;
    let fixed = world.bodies.insert(RigidBodyBuilder::fixed());
    for (x, y, hx, hy) in walls(chains.container) {
        let wall = ColliderBuilder::cuboid(hx, hy)
            .translation(Vector::new(x, y))
            .friction(chains.friction);
        world
            .colliders
            .insert_with_parent(wall, fixed, &mut world.bodies);
    }
    let mut handles: Vec<Vec<(RigidBodyHandle, f32)>> = Vec::new();
    for strand in &chains.strands {
        let mut links = Vec::new();
        for pair in strand.windows(2) {
            let (a, b) = (
                Vector::new(pair[0][0], pair[0][1]),
                Vector::new(pair[1][0], pair[1][1]),
            );
            let length = (b - a).length();
            let angle = (b - a).y.atan2((b - a).x);
            let body = RigidBodyBuilder::dynamic()
                .translation((a + b) * 0.5)
                .rotation(angle);
            let handle = world.bodies.insert(body);
            let collider = ColliderBuilder::capsule_x(length / 2.0, chains.radius)
                .mass(chains.link_mass)
                .friction(chains.friction);
            world
                .colliders
                .insert_with_parent(collider, handle, &mut world.bodies);
            links.push((handle, length));
        }
        for pair in links.windows(2) {
            let joint = RevoluteJointBuilder::new()
                .local_anchor1(Vector::new(pair[0].1 / 2.0, 0.0))
                .local_anchor2(Vector::new(-pair[1].1 / 2.0, 0.0))
                .contacts_enabled(false);
            world
                .impulse_joints
                .insert(pair[0].0, pair[1].0, joint, true);
        }
        handles.push(links);
    }
    let mut run = EngineRun::new(
        "rapier2d",
        "revolute impulse joints, capsule links",
        length_unit,
        rapier2d::rayon::current_num_threads(),
    );
    let lengths: Vec<Vec<f32>> = (handles.iter())
        .map(|links| links.iter().map(|l| l.1).collect())
        .collect();
    run.drive(chains, &lengths, steps, |segments| {
        let began = Instant::now();
        world.step();
        let wall = began.elapsed().as_secs_f64();
        segments.extend(handles.iter().map(|links| {
            links
                .iter()
                .map(|&(h, length)| {
                    let pose = world.bodies[h].position();
                    let half = Vector::new(length / 2.0, 0.0);
                    let (a, b) = (pose.transform_point(-half), pose.transform_point(half));
                    [[a.x, a.y], [b.x, b.y]]
                })
                .collect()
        }));
        wall
    });
    run
}

/// The container's four sides as (centre x, centre y, half width, half height) of
/// cuboids half a box thick outside it.
pub fn walls(container: ([f32; 2], [f32; 2])) -> [(f32, f32, f32, f32); 4] {
    let ([x0, y0], [x1, y1]) = container;
    let (w, h) = (x1 - x0, y1 - y0);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let t = 0.5 * w.max(h);
    [
        (cx, y0 - t, 0.5 * w + 2.0 * t, t),
        (cx, y1 + t, 0.5 * w + 2.0 * t, t),
        (x0 - t, cy, t, 0.5 * h + 2.0 * t),
        (x1 + t, cy, t, 0.5 * h + 2.0 * t),
    ]
}
