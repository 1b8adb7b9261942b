//! Windowed presentation (the `render` feature): gizmo drawing of the strands, an egui
//! panel with controls and live figures, mouse tools, keyboard shortcuts, frame export
//! and an opt-in screenshot for scripted checks.
//!
//! Two plugins, both optional: [`StrandsRenderPlugin`] draws; [`StrandsUiPlugin`] adds
//! the panel, the tools and the shortcuts. The simulation plugin depends on neither.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_strands::prelude::*;
//! use bevy_strands::render::{ActiveScene, StrandsRenderPlugin, StrandsUiPlugin, window_plugins};
//!
//! App::new()
//!     .add_plugins(window_plugins("long strand"))
//!     .add_plugins((StrandsPlugin::default(), StrandsRenderPlugin, StrandsUiPlugin))
//!     .insert_resource(ActiveScene::builtin("long_strand"))
//!     .run();
//! ```

mod draw;
mod screenshot;
mod tools;
mod ui;

use bevy::app::PluginGroupBuilder;
use bevy::prelude::*;
use bevy::window::WindowResolution;

use crate::scene::{Scene, spawn_scene};
use crate::scenes::builtin;

pub use draw::{DrawSettings, StrandsRenderPlugin};
pub use screenshot::ScreenshotPlugin;
pub use tools::{Tool, ToolState};
pub use ui::{StrandsUiPlugin, UiLayout};

/// Bevy's default plugins for an example window: 1280×720, titled, no vsync wait
/// beyond the display's.
pub fn window_plugins(title: &str) -> PluginGroupBuilder {
    DefaultPlugins.set(WindowPlugin {
        primary_window: Some(Window {
            title: format!("bevy_strands: {title}"),
            resolution: WindowResolution::new(1280, 720),
            ..default()
        }),
        ..default()
    })
}

/// The scene shown: spawned at start-up and again on reset.
#[derive(Resource, Clone, Debug)]
pub struct ActiveScene {
    /// The scene.
    pub scene: Scene,
}

impl ActiveScene {
    /// A built-in scenario (see `strands list`).
    pub fn builtin(name: &str) -> Self {
        let scene = builtin(name)
            .unwrap_or_else(|| panic!("no built-in scene '{name}'"))
            .scene()
            .unwrap_or_else(|e| panic!("{e}"));
        Self { scene }
    }
}

/// Spawn the active scene (start-up).
pub fn spawn_active_scene(world: &mut World) {
    let Some(active) = world.get_resource::<ActiveScene>().cloned() else {
        return;
    };
    if let Err(e) = spawn_scene(world, &active.scene) {
        error!("bevy_strands: {e}");
    }
}
