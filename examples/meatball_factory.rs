//! Spaghetti and spinning triangle meatballs pile up together.
//!
//! `cargo run --release --example meatball_factory --features render`. The panel on the right
//! holds the controls, the live figures and the mouse tools.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::window::{ActiveScenario, DemoPlugins, window_plugins};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("meatball factory"))
        .add_plugins((StrandsPlugin::default(), DemoPlugins))
        .insert_resource(ActiveScenario::builtin("meatball_factory").expect("a built-in scenario"))
        .run()
}
