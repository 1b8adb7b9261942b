//! One free strand falls tilted onto the floor and piles up.
//!
//! `cargo run --release --example long_strand --features render`. The panel on the right
//! holds the controls, the live figures and the mouse tools.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::render::{ActiveScene, StrandsRenderPlugin, StrandsUiPlugin, window_plugins};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("long strand"))
        .add_plugins((
            StrandsPlugin::default(),
            StrandsRenderPlugin,
            StrandsUiPlugin,
        ))
        .insert_resource(ActiveScene::builtin("long_strand"))
        .run()
}
