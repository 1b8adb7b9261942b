//! The web demo: the spaghetti factory, the meatball factory and a rope to drag, in one
//! page with the panel (its "scene" menu switches between them).
//!
//! Built for the browser by `scripts/web.sh` (wasm32, WebGL2, one thread), which writes
//! a static page to `target/web-demo/`; `?scene=meatball_factory` in the address picks the
//! first scene. On the desktop: `cargo run --release --example web --features render
//! [scene]`. The live figures also go to the page as JSON (`#strands-figures`).

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::window::page::{PageFiguresPlugin, requested_scene};
use bevy_strands_app::window::{DemoPlugins, ScenarioMenu, UiKeys, window_plugins};

/// The page's scenes: the two factories and a strand to drag around.
const SCENES: [&str; 3] = ["spaghetti_factory", "meatball_factory", "long_strand"];

fn main() -> AppExit {
    let mut app = App::new();
    // The plugins first: an unknown scene is then said in the log (the browser's console).
    app.add_plugins(window_plugins("web demo")).add_plugins((
        StrandsPlugin::default(),
        DemoPlugins,
        PageFiguresPlugin,
    ));
    // Small scenes: every step is checked for crossed edges, and the page shows it.
    let menu = ScenarioMenu {
        check_crossings: true,
        ..ScenarioMenu::builtin(&SCENES).expect("built-in scenarios")
    };
    let name = requested_scene().unwrap_or_else(|| SCENES[0].to_string());
    let active = match menu.scenario(&name) {
        Ok(active) => active,
        Err(e) => {
            error!("bevy_strands: {e}; showing {}", SCENES[0]);
            menu.scenario(SCENES[0]).expect("a built-in scenario")
        }
    };
    app.insert_resource(active)
        .insert_resource(menu)
        // A page has no folder to record frames into.
        .insert_resource(UiKeys {
            record: None,
            ..default()
        })
        .run()
}
