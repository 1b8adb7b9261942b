//! `long_strand` beside Rapier's impulse-joint chain of the same rope, in one run.
//!
//! `cargo run --release -p bevy_strands_compare [-- SECONDS]` (10 s by default) runs
//! the built-in `long_strand` scenario on one thread with the crossing check off, then
//! the same rope in rapier2d: 59 capsule links of 15 mm (radius 2 mm, half the strands'
//! 4 mm thickness), joined end to end by revolute impulse joints, tilted 75° with its
//! lower end at (0.35, 0.10), inside the unit box, friction 0.3, the same 1/300 s step.
//! It prints both engines' particle-steps per second (a link end counts as a particle)
//! and their worst relative stretch: an edge's length error for the strand, the gap
//! between the two anchors of a joint over the link length for Rapier.

use std::time::Instant;

use bevy_strands_app::runner::{RunOptions, run};
use rapier2d::prelude::*;

const PARTICLES: usize = 60;
const SPACING: f32 = 0.015;
const RADIUS: f32 = 0.002;
const DT: f32 = 1.0 / 300.0;

fn main() {
    let seconds: f64 = match std::env::args().nth(1).map(|a| a.parse()) {
        None => 10.0,
        Some(Ok(s)) if s > 0.0 && f64::is_finite(s) => s,
        Some(_) => {
            eprintln!("usage: bevy_strands_compare [SECONDS > 0]");
            std::process::exit(2);
        }
    };
    let options = RunOptions {
        scenario: "long_strand".into(),
        seconds: Some(seconds),
        threads: Some(1),
        check_crossings: false,
        ..Default::default()
    };
    let report = match run(&options, |_| {}) {
        Ok(report) => report,
        Err(error) => {
            eprintln!("long_strand: {error}");
            std::process::exit(1);
        }
    };
    let strands = report.particle_steps_per_second;
    println!(
        "bevy_strands long_strand: {} particles, {} steps, {:.3} s wall, {:.3} M particle-steps/s, max relative length error {:.2e}",
        report.particles,
        report.steps,
        report.wall_seconds,
        strands / 1e6,
        report.max_rel_length_error
    );
    let (wall, steps, stretch) = rapier_chain(report.steps);
    let rapier = (PARTICLES as u64 * steps) as f64 / wall;
    println!(
        "rapier2d impulse-joint chain: {} links, {steps} steps, {wall:.3} s wall, {:.3} M particle-steps/s, max relative stretch {stretch:.2e}",
        PARTICLES - 1,
        rapier / 1e6
    );
    println!("ratio: {:.2}x", strands / rapier);
}

/// Step Rapier's chain `steps` times: the wall time of the steps alone, and the worst
/// joint gap over the link length at any step end.
fn rapier_chain(steps: u64) -> (f64, u64, f32) {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = DT;
    // The unit box: floor, walls and ceiling as fixed cuboids outside it.
    let fixed = world.bodies.insert(RigidBodyBuilder::fixed());
    for (x, y, hx, hy) in [
        (0.5, -0.5, 1.0, 0.5),
        (0.5, 1.5, 1.0, 0.5),
        (-0.5, 0.5, 0.5, 1.0),
        (1.5, 0.5, 0.5, 1.0),
    ] {
        let wall = ColliderBuilder::cuboid(hx, hy)
            .translation(Vector::new(x, y))
            .friction(0.3);
        world
            .colliders
            .insert_with_parent(wall, fixed, &mut world.bodies);
    }
    let angle = 75f32.to_radians();
    let along = Vector::new(angle.cos(), angle.sin());
    let start = Vector::new(0.35, 0.10 + RADIUS);
    let mut links = Vec::new();
    for k in 0..PARTICLES - 1 {
        let centre = start + along * (SPACING * (k as f32 + 0.5));
        let body = RigidBodyBuilder::dynamic()
            .translation(centre)
            .rotation(angle);
        let handle = world.bodies.insert(body);
        // Mass 1/60 kg per link end, as the strand's particles.
        let collider = ColliderBuilder::capsule_x(SPACING / 2.0, RADIUS)
            .mass(1.0 / PARTICLES as f32)
            .friction(0.3);
        world
            .colliders
            .insert_with_parent(collider, handle, &mut world.bodies);
        links.push(handle);
    }
    let half = Vector::new(SPACING / 2.0, 0.0);
    for pair in links.windows(2) {
        let joint = RevoluteJointBuilder::new()
            .local_anchor1(half)
            .local_anchor2(-half)
            .contacts_enabled(false);
        world.impulse_joints.insert(pair[0], pair[1], joint, true);
    }
    let (mut stretch, mut wall) = (0.0f32, 0.0);
    for _ in 0..steps {
        let began = Instant::now();
        world.step();
        wall += began.elapsed().as_secs_f64();
        for pair in links.windows(2) {
            let a = world.bodies[pair[0]].position().transform_point(half);
            let b = world.bodies[pair[1]].position().transform_point(-half);
            stretch = stretch.max((a - b).length() / SPACING);
        }
    }
    // Where the rope ended: it must lie on the floor inside the box, not fly off.
    let heights = links.iter().map(|&h| world.bodies[h].translation().y);
    let top = heights.fold(f32::MIN, f32::max);
    assert!(
        (0.0..1.0).contains(&top),
        "Rapier's chain left the box (highest link at y = {top})"
    );
    (wall, steps, stretch)
}
