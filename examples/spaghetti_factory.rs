//! The spaghetti factory: an inlet extrudes strands that pile up in the box.
//!
//! `cargo run --release --example spaghetti_factory --features render`. The panel on the right
//! holds the controls, the live figures and the mouse tools.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::window::{ActiveScenario, DemoPlugins, window_plugins};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("spaghetti factory"))
        .add_plugins((StrandsPlugin::default(), DemoPlugins))
        .insert_resource(ActiveScenario::builtin("spaghetti_factory").expect("a built-in scenario"))
        .run()
}
