//! The windowed demos (feature `render`): the scene drawn with the library's gizmo
//! drawing, a camera that keeps it in view beside an egui panel with controls and live
//! figures, mouse tools, keyboard shortcuts, frame export and an opt-in screenshot for
//! scripted checks.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_strands::prelude::*;
//! use bevy_strands_app::window::{ActiveScenario, DemoPlugins, window_plugins};
//!
//! App::new()
//!     .add_plugins(window_plugins("long strand"))
//!     .add_plugins((StrandsPlugin::default(), DemoPlugins))
//!     .insert_resource(ActiveScenario::builtin("long_strand").expect("a built-in scenario"))
//!     .run();
//! ```

#[cfg(any(feature = "avian", feature = "rapier"))]
pub mod bodies;
pub mod command;
mod controls;
mod layout;
mod pace;
pub mod page;
mod screenshot;
mod tools;
#[cfg(feature = "render")]
mod ui;
mod view;
#[cfg(all(feature = "web", target_arch = "wasm32"))]
mod web_plugins;

use bevy::app::PluginGroupBuilder;
use bevy::prelude::*;
use bevy::window::WindowResolution;
use bevy_strands::render::StrandsDebugDrawPlugin;

use crate::builtin::{builtin, builtin_names};
use crate::scenario::{Scenario, ScenarioError};
use crate::scenes::ScenesPlugin;
use crate::spawn::spawn_scenario;

pub use controls::{FrameExport, StrandsUiPlugin, UiKeys, reset, switch_scenario};
pub use layout::UiLayout;
pub use pace::{PacePlugin, RealTimeFactor};
pub use screenshot::ScreenshotPlugin;
pub use tools::{Tool, ToolState};
pub use view::DemoViewPlugin;

/// Bevy's default plugins for an example window: 1280×720, titled. On the web the
/// window is the page's `<canvas id="strands">`, sized to its parent, and the list is
/// the page's own (see `web_plugins`).
pub fn window_plugins(title: &str) -> PluginGroupBuilder {
    let window = WindowPlugin {
        primary_window: Some(Window {
            title: format!("bevy_strands: {title}"),
            resolution: WindowResolution::new(1280, 720),
            canvas: cfg!(target_arch = "wasm32").then(|| "#strands".to_string()),
            fit_canvas_to_parent: cfg!(target_arch = "wasm32"),
            ..default()
        }),
        ..default()
    };
    #[cfg(all(feature = "web", target_arch = "wasm32"))]
    return web_plugins::WebPlugins.set(window);
    #[cfg(not(all(feature = "web", target_arch = "wasm32")))]
    DefaultPlugins.set(window)
}

/// Everything a demo window adds to the simulation: the scenario logic, the strands'
/// debug drawing, the demo's camera and bodies, and the panel with its tools.
pub struct DemoPlugins;

impl PluginGroup for DemoPlugins {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(ScenesPlugin)
            .add(StrandsDebugDrawPlugin)
            .add(DemoViewPlugin)
            .add(StrandsUiPlugin)
            .add(PacePlugin)
    }
}

/// The scenario shown: spawned at start-up and again on reset.
#[derive(Resource, Clone, Debug)]
pub struct ActiveScenario {
    /// The scenario.
    pub scenario: Scenario,
}

impl ActiveScenario {
    /// A built-in scenario (see `strands list`).
    pub fn builtin(name: &str) -> Result<Self, ScenarioError> {
        let scene = builtin(name).ok_or_else(|| {
            ScenarioError::new(
                name,
                "name",
                format!(
                    "no built-in scenario of that name; valid: {}",
                    builtin_names().join(", ")
                ),
            )
        })?;
        Ok(Self {
            scenario: scene.scenario()?,
        })
    }
}

/// The scenarios the panel offers to switch between (none when absent).
#[derive(Resource, Clone, Debug, Default)]
pub struct ScenarioMenu {
    /// Built-in scenario names, in the menu's order.
    pub names: Vec<String>,
    /// Whether the scenarios it starts check for crossed edges every step.
    pub check_crossings: bool,
}

impl ScenarioMenu {
    /// A menu of built-in scenarios; an unknown name is refused with the valid ones.
    pub fn builtin(names: &[&str]) -> Result<Self, ScenarioError> {
        for name in names {
            ActiveScenario::builtin(name)?;
        }
        Ok(Self {
            names: names.iter().map(|n| n.to_string()).collect(),
            check_crossings: false,
        })
    }

    /// The menu's scenario `name` as this menu starts it; a name the menu does not
    /// offer is refused with the ones it does.
    pub fn scenario(&self, name: &str) -> Result<ActiveScenario, ScenarioError> {
        if !self.names.iter().any(|n| n == name) {
            return Err(ScenarioError::new(
                name,
                "name",
                format!("not a scene of this demo; valid: {}", self.names.join(", ")),
            ));
        }
        let mut active = ActiveScenario::builtin(name)?;
        active.scenario.collisions.check_crossings |= self.check_crossings;
        Ok(active)
    }
}

/// Spawn the active scenario (start-up, reset).
pub fn spawn_active_scenario(world: &mut World) {
    let Some(active) = world.get_resource::<ActiveScenario>().cloned() else {
        return;
    };
    if let Err(e) = spawn_scenario(world, &active.scenario) {
        error!("bevy_strands: {e}");
    }
}
