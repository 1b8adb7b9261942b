//! A body on a circular path drags 400 stiff hairs rooted on its rim, one step of 1/60 s a
//! tick.
//!
//! `cargo run --release --example furry_creature --features render`. The panel on the right
//! holds the controls, the live figures and the mouse tools.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::window::{ActiveScenario, DemoPlugins, window_plugins};

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("furry creature"))
        .add_plugins((StrandsPlugin::default(), DemoPlugins))
        .insert_resource(ActiveScenario::builtin("furry_creature").expect("a built-in scenario"))
        .run()
}
