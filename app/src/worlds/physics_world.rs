//! The `physics_world` example's world: avian bodies and strands coupled both ways. A
//! ground and two posts (static bodies), a rope bridge between the posts, five crates
//! dropped on it one every 1.2 s, and a crane (a kinematic beam driven to and fro)
//! swinging a heavy crate on a rope. Avian and the strands each at 60 Hz, the strands
//! in 10 substeps. The layout and the ropes are [`bodies_world`](super::bodies_world)'s.

use avian2d::prelude::*;
use bevy::prelude::*;
use bevy_strands::prelude::*;

use super::bodies_world::{
    BEAM, DENSITIES, GROUND, POSTS, crane_speed, drop_at, load_centre, spawn_ropes,
};
pub use super::bodies_world::{
    BodiesWorld as PhysicsWorld, CRATE, Crane, DROP_TICKS, DROPS, DroppedCrate, VIEW,
    bodies_world_config as physics_world_config,
};

/// Drops the crates and drives the crane, in `FixedUpdate`.
pub struct PhysicsWorldPlugin;

impl Plugin for PhysicsWorldPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(FixedUpdate, (drop_crates, drive_crane));
    }
}

/// Spawn the world's bodies and strands.
pub fn spawn_physics_world(commands: &mut Commands) -> PhysicsWorld {
    // Static bodies: the ground and the bridge's two posts. Strands collide with them
    // as the crates do.
    let mut solid = |centre: Vec2, size: Vec2| {
        commands
            .spawn((
                RigidBody::Static,
                Collider::rectangle(size.x, size.y),
                CollidesWithStrands::default(),
                Transform::from_translation(centre.extend(-0.5)),
            ))
            .id()
    };
    let ground = solid(GROUND.0, GROUND.1);
    let posts = POSTS.0.map(|x| solid(Vec2::new(x, POSTS.1), POSTS.2));
    // The crane: a kinematic beam, a rope hung from it, a heavy crate on the rope.
    let beam = commands
        .spawn((
            Crane,
            RigidBody::Kinematic,
            Collider::rectangle(BEAM.1.x, BEAM.1.y),
            Transform::from_translation(BEAM.0.extend(-0.5)),
        ))
        .id();
    let load = commands
        .spawn((
            RigidBody::Dynamic,
            Collider::rectangle(CRATE, CRATE),
            ColliderDensity(DENSITIES.1),
            CollidesWithStrands::default(),
            Transform::from_translation(load_centre().extend(0.6)),
        ))
        .id();
    let (bridge, line) = spawn_ropes(commands, beam, load);
    PhysicsWorld {
        ground,
        posts,
        bridge,
        beam,
        load,
        line,
    }
}

/// A crate every 1.2 s over the bridge, five in all.
pub fn drop_crates(mut commands: Commands, mut ticks: Local<u32>) {
    if let Some(x) = drop_at(&mut ticks) {
        commands.spawn((
            DroppedCrate,
            RigidBody::Dynamic,
            Collider::rectangle(CRATE, CRATE),
            ColliderDensity(DENSITIES.0),
            CollidesWithStrands::default(),
            Transform::from_xyz(x, 1.25, 0.6),
        ));
    }
}

/// The crane's beam runs to and fro.
pub fn drive_crane(time: Res<Time<Fixed>>, mut beam: Query<&mut LinearVelocity, With<Crane>>) {
    for mut velocity in &mut beam {
        velocity.0.x = crane_speed(time.elapsed_secs());
    }
}
