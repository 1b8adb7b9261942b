//! The looks of the bodies-and-ropes worlds (`physics_world`, `rapier_world`): a
//! camera on the world, sprites on the bodies, ribbons on the ropes. Either engine's
//! world is dressed the same.

use bevy::camera::ScalingMode;
use bevy::prelude::*;
use bevy_strands::ribbon::StrandRibbon;

use crate::worlds::bodies_world::{BEAM, BodiesWorld, CRATE, DroppedCrate, GROUND, POSTS, VIEW};

/// Dresses a [`BodiesWorld`] and each crate dropped on it.
pub struct BodiesLooksPlugin;

impl Plugin for BodiesLooksPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(ClearColor(Color::srgb(0.55, 0.7, 0.85)))
            .add_systems(Update, dress_crates);
    }
}

/// The camera, and the world's sprites and ribbons.
pub fn dress_bodies_world(
    commands: &mut Commands,
    materials: &mut Assets<ColorMaterial>,
    world: &BodiesWorld,
) {
    commands.spawn((
        Camera2d,
        Projection::Orthographic(OrthographicProjection {
            scaling_mode: ScalingMode::AutoMin {
                min_width: VIEW.x,
                min_height: VIEW.y,
            },
            ..OrthographicProjection::default_2d()
        }),
        Transform::from_translation((VIEW / 2.0).extend(0.0)),
    ));
    let wood = Color::srgb(0.4, 0.26, 0.13);
    commands
        .entity(world.ground)
        .insert(Sprite::from_color(Color::srgb(0.3, 0.45, 0.2), GROUND.1));
    for post in world.posts {
        commands
            .entity(post)
            .insert(Sprite::from_color(wood, POSTS.2));
    }
    commands
        .entity(world.beam)
        .insert(Sprite::from_color(wood, BEAM.1));
    commands.entity(world.load).insert(Sprite::from_color(
        Color::srgb(0.55, 0.35, 0.2),
        Vec2::splat(CRATE),
    ));
    let rope = materials.add(Color::srgb(0.62, 0.45, 0.25));
    let ribbon = |width: f64| StrandRibbon {
        width,
        repeat: 2.0 * width,
        z: 0.5,
        ..default()
    };
    commands
        .entity(world.bridge)
        .insert((ribbon(0.014), MeshMaterial2d(rope.clone())));
    commands
        .entity(world.line)
        .insert((ribbon(0.01), MeshMaterial2d(rope)));
}

/// Each dropped crate gets its sprite.
fn dress_crates(mut commands: Commands, crates: Query<Entity, Added<DroppedCrate>>) {
    for entity in &crates {
        commands.entity(entity).insert(Sprite::from_color(
            Color::srgb(0.72, 0.5, 0.25),
            Vec2::splat(CRATE),
        ));
    }
}
