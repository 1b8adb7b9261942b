//! One free strand falls tilted onto the floor and piles up.
//!
//! `cargo run --release --features render --example long_strand`. The panel on the right
//! holds the controls, the live figures and the mouse tools.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::window::{ActiveScenario, DemoPlugins, window_plugins};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("long strand"))
        .add_plugins((StrandsPlugin::default(), DemoPlugins))
        .insert_resource(ActiveScenario::builtin("long_strand").expect("a built-in scenario"))
        .run()
}
