//! An empty box to build in: create particles, edges and hairs with the mouse.
//!
//! `cargo run --release --example sandbox --features render`. The panel on the right
//! holds the controls, the live figures and the mouse tools.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::window::{ActiveScenario, DemoPlugins, window_plugins};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("sandbox"))
        .add_plugins((StrandsPlugin::default(), DemoPlugins))
        .insert_resource(ActiveScenario::builtin("sandbox").expect("a built-in scenario"))
        .run()
}
