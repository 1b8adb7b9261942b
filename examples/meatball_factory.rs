//! Spaghetti and spinning triangle meatballs pile up together.
//!
//! `cargo run --release --example meatball_factory --features render`. The panel on the right
//! holds the controls, the live figures and the mouse tools.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::render::{ActiveScene, StrandsRenderPlugin, StrandsUiPlugin, window_plugins};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("meatball factory"))
        .add_plugins((
            StrandsPlugin::default(),
            StrandsRenderPlugin,
            StrandsUiPlugin,
        ))
        .insert_resource(ActiveScene::builtin("meatball_factory"))
        .run()
}
