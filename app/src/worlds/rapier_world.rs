//! The `rapier_world` example's world: the `physics_world` example's bodies and
//! strands in bevy_rapier2d — a rope bridge between two fixed posts, five crates
//! dropped on it, and a crane (a velocity-driven kinematic beam) swinging a heavy crate
//! on a rope. Rapier (in the fixed schedule) and the strands each at 60 Hz, the strands
//! in 10 substeps. The layout and the ropes are [`bodies_world`](super::bodies_world)'s.

use bevy::prelude::*;
use bevy_rapier2d::prelude::{
    Collider, ColliderMassProperties, NoUserData, RapierPhysicsPlugin, RigidBody, TimestepMode,
    Velocity,
};
use bevy_strands::prelude::*;

use super::bodies_world::{
    BEAM, DENSITIES, GROUND, POSTS, crane_speed, drop_at, load_centre, spawn_ropes,
};
pub use super::bodies_world::{
    BodiesWorld as RapierWorld, CRATE, Crane, DroppedCrate, VIEW,
    bodies_world_config as rapier_world_config,
};

/// Rapier in the fixed schedule, one step a tick, and the world's drops and crane.
pub struct RapierWorldPlugin;

impl Plugin for RapierWorldPlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins(RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule())
            .insert_resource(TimestepMode::Fixed {
                dt: 1.0 / 60.0,
                substeps: 1,
            })
            .add_systems(FixedUpdate, (drop_crates, drive_crane));
    }
}

/// Half a box's size, as Rapier's cuboids take it.
fn cuboid(size: Vec2) -> Collider {
    Collider::cuboid(0.5 * size.x, 0.5 * size.y)
}

/// Spawn the world's bodies and strands.
pub fn spawn_rapier_world(commands: &mut Commands) -> RapierWorld {
    let mut solid = |centre: Vec2, size: Vec2| {
        commands
            .spawn((
                RigidBody::Fixed,
                cuboid(size),
                CollidesWithStrands::default(),
                Transform::from_translation(centre.extend(-0.5)),
            ))
            .id()
    };
    let ground = solid(GROUND.0, GROUND.1);
    let posts = POSTS.0.map(|x| solid(Vec2::new(x, POSTS.1), POSTS.2));
    let beam = commands
        .spawn((
            Crane,
            RigidBody::KinematicVelocityBased,
            cuboid(BEAM.1),
            Transform::from_translation(BEAM.0.extend(-0.5)),
        ))
        .id();
    let load = commands
        .spawn((
            RigidBody::Dynamic,
            cuboid(Vec2::splat(CRATE)),
            ColliderMassProperties::Density(DENSITIES.1),
            CollidesWithStrands::default(),
            Transform::from_translation(load_centre().extend(0.6)),
        ))
        .id();
    let (bridge, line) = spawn_ropes(commands, beam, load);
    RapierWorld {
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
            cuboid(Vec2::splat(CRATE)),
            ColliderMassProperties::Density(DENSITIES.0),
            CollidesWithStrands::default(),
            Transform::from_xyz(x, 1.25, 0.6),
        ));
    }
}

/// The crane's beam runs to and fro.
pub fn drive_crane(time: Res<Time<Fixed>>, mut beam: Query<&mut Velocity, With<Crane>>) {
    for mut velocity in &mut beam {
        velocity.linear.x = crane_speed(time.elapsed_secs());
    }
}
