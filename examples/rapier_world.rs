//! Strands in a bevy_rapier2d world — the `physics_world` example's world with Rapier
//! stepping the bodies: crates dropped on a rope bridge land on it and rest on it; a
//! crane (a velocity-driven kinematic Rapier body) swings a heavy crate on a rope.
//! Rapier runs in the fixed schedule at 60 Hz, the strands in 10 substeps a tick,
//! coupled both ways by `StrandsRapierPlugin`.
//!
//! `cargo run --release --features render,rapier --example rapier_world`

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::ribbon::StrandRibbonPlugin;
use bevy_strands_app::window::bodies::{BodiesLooksPlugin, dress_bodies_world};
use bevy_strands_app::window::{ScreenshotPlugin, window_plugins};
use bevy_strands_app::worlds::rapier_world::{
    RapierWorldPlugin, rapier_world_config, spawn_rapier_world,
};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("strands in a Rapier world"))
        .add_plugins((
            StrandsPlugin::default(),
            RapierWorldPlugin,
            StrandsRapierPlugin::default(),
            StrandRibbonPlugin,
            ScreenshotPlugin,
            BodiesLooksPlugin,
        ))
        .insert_resource(Time::<Fixed>::from_hz(60.0))
        .insert_resource(rapier_world_config())
        .add_systems(Startup, setup)
        .run()
}

/// The world, dressed.
fn setup(mut commands: Commands, mut materials: ResMut<Assets<ColorMaterial>>) {
    let world = spawn_rapier_world(&mut commands);
    dress_bodies_world(&mut commands, &mut materials, &world);
}
