//! Strands in an avian2d world: crates dropped on a rope bridge land on it, sag it and
//! rest on it; a crane (a kinematic avian body) swings a crate on a rope — the crate's
//! weight hangs on the rope, the rope's pull swings the crate. Avian steps the bodies,
//! the strands step the ropes, each at 60 Hz (the strands in 10 substeps), coupled
//! both ways by `StrandsAvianPlugin`.
//!
//! `cargo run --release --features render,avian --example physics_world`

use avian2d::prelude::*;
use bevy::camera::ScalingMode;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::ribbon::{StrandRibbon, StrandRibbonPlugin};
use bevy_strands_app::window::{ScreenshotPlugin, window_plugins};
use bevy_strands_app::worlds::physics_world::{
    CRATE, DroppedCrate, PhysicsWorldPlugin, VIEW, physics_world_config, spawn_physics_world,
};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("strands in an avian world"))
        .add_plugins((
            PhysicsPlugins::default(),
            StrandsPlugin::default(),
            StrandsAvianPlugin::default(),
            StrandRibbonPlugin,
            ScreenshotPlugin,
            PhysicsWorldPlugin,
        ))
        .insert_resource(Time::<Fixed>::from_hz(60.0))
        .insert_resource(physics_world_config())
        .insert_resource(ClearColor(Color::srgb(0.55, 0.7, 0.85)))
        .add_systems(Startup, setup)
        .add_systems(Update, dress_crates)
        .run()
}

/// The world, dressed: sprites on the bodies, ribbons on the ropes.
fn setup(mut commands: Commands, mut materials: ResMut<Assets<ColorMaterial>>) {
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
    let world = spawn_physics_world(&mut commands);
    let wood = Color::srgb(0.4, 0.26, 0.13);
    commands.entity(world.ground).insert(Sprite::from_color(
        Color::srgb(0.3, 0.45, 0.2),
        Vec2::new(2.4, 0.1),
    ));
    for post in world.posts {
        commands
            .entity(post)
            .insert(Sprite::from_color(wood, Vec2::new(0.04, 0.6)));
    }
    commands
        .entity(world.beam)
        .insert(Sprite::from_color(wood, Vec2::new(0.3, 0.04)));
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
