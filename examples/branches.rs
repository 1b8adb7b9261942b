//! Branching hairs (trees), a ladder and a truss (graphs): structures beyond single strands.
//!
//! `cargo run --release --example branches --features render`. The panel on the right
//! holds the controls, the live figures and the mouse tools.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::window::{ActiveScenario, DemoPlugins, window_plugins};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("branches"))
        .add_plugins((StrandsPlugin::default(), DemoPlugins))
        .insert_resource(ActiveScenario::builtin("branches").expect("a built-in scenario"))
        .run()
}
