//! Strands in an avian2d world: crates dropped on a rope bridge land on it, sag it and
//! rest on it; a crane (a kinematic avian body) swings a crate on a rope — the crate's
//! weight hangs on the rope, the rope's pull swings the crate. Avian steps the bodies,
//! the strands step the ropes, each at 60 Hz (the strands in 10 substeps), coupled
//! both ways by `StrandsAvianPlugin`. The same world in Rapier: `rapier_world`.
//!
//! `cargo run --release --features render,avian --example physics_world`

use avian2d::prelude::*;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::ribbon::StrandRibbonPlugin;
use bevy_strands_app::window::bodies::{BodiesLooksPlugin, dress_bodies_world};
use bevy_strands_app::window::{ScreenshotPlugin, window_plugins};
use bevy_strands_app::worlds::physics_world::{
    PhysicsWorldPlugin, physics_world_config, spawn_physics_world,
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
            BodiesLooksPlugin,
        ))
        .insert_resource(Time::<Fixed>::from_hz(60.0))
        .insert_resource(physics_world_config())
        .add_systems(Startup, setup)
        .run()
}

/// The world, dressed.
fn setup(mut commands: Commands, mut materials: ResMut<Assets<ColorMaterial>>) {
    let world = spawn_physics_world(&mut commands);
    dress_bodies_world(&mut commands, &mut materials, &world);
}
