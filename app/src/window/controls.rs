//! What the demos' controls do, with or without the egui panel: the keyboard shortcuts,
//! restarting or switching the scene, frame export and the length error's history. The
//! panel (feature `render`) and the web page's own controls both act through these.

use std::path::PathBuf;

use bevy::prelude::*;

use bevy_strands::metrics::LengthErrorHistory;
use bevy_strands::prelude::*;

use super::command::SUBSTEPS_RANGE;
use super::layout::UiLayout;
#[cfg(not(target_arch = "wasm32"))]
use super::screenshot::ScreenshotPlugin;
use super::tools::{ToolState, use_tools};
use super::{ActiveScenario, ScenarioMenu, spawn_active_scenario};
use crate::export::{FrameSettings, Recorder};
use crate::scenes::furry_creature::FurryCreature;
use crate::scenes::meatball_factory::MeatballFactory;
use crate::scenes::spaghetti_factory::SpaghettiFactory;

/// PNG frames written while recording (the E key).
#[derive(Resource, Default)]
pub struct FrameExport {
    recorder: Option<Recorder>,
    /// Where frames go.
    pub directory: PathBuf,
    /// The last export error, shown in the panel.
    pub message: Option<String>,
}

impl FrameExport {
    /// Whether frames are being written.
    pub fn recording(&self) -> bool {
        self.recorder.is_some()
    }
}

/// Samples of the error plot kept: older ones are dropped.
const PLOT_SAMPLES: usize = 20_000;

/// The panel's keyboard shortcuts; `None` turns one off, [`UiKeys::none`] all of them.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct UiKeys {
    /// Run or pause the simulation.
    pub pause: Option<KeyCode>,
    /// Restart the scenario.
    pub reset: Option<KeyCode>,
    /// Start or stop recording frames.
    pub record: Option<KeyCode>,
    /// One more substep per tick.
    pub more_substeps: Option<KeyCode>,
    /// One substep fewer per tick.
    pub fewer_substeps: Option<KeyCode>,
}

impl Default for UiKeys {
    fn default() -> Self {
        Self {
            pause: Some(KeyCode::Space),
            reset: Some(KeyCode::KeyR),
            record: Some(KeyCode::KeyE),
            more_substeps: Some(KeyCode::Equal),
            fewer_substeps: Some(KeyCode::Minus),
        }
    }
}

impl UiKeys {
    /// No shortcuts: the game's keys are the game's.
    pub fn none() -> Self {
        Self {
            pause: None,
            reset: None,
            record: None,
            more_substeps: None,
            fewer_substeps: None,
        }
    }

    /// The help line the panel shows.
    pub fn help(&self) -> String {
        let name = |key: Option<KeyCode>, what: &str| {
            key.map(|k| format!("{} {what}", format!("{k:?}").trim_start_matches("Key")))
        };
        [
            name(self.pause, "run/pause"),
            name(self.reset, "reset"),
            name(self.record, "record frames"),
            name(self.more_substeps, "more substeps"),
            name(self.fewer_substeps, "fewer substeps"),
        ]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join(" · ")
    }
}

/// The demos' controls: the mouse tools, the shortcuts, frame export, the opt-in
/// screenshot and, with the `render` feature, the egui panel.
pub struct StrandsUiPlugin;

impl Plugin for StrandsUiPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ToolState>()
            .init_resource::<UiKeys>()
            .init_resource::<UiLayout>()
            .init_resource::<LengthErrorHistory>()
            .insert_resource(FrameExport {
                directory: PathBuf::from("frames"),
                ..default()
            })
            .add_systems(Update, (shortcuts, use_tools, trim_history));
        #[cfg(feature = "render")]
        app.add_plugins(super::ui::PanelPlugin);
        // A page has no folder to write frames or screenshots into, and leaves the
        // encoders out.
        #[cfg(not(target_arch = "wasm32"))]
        app.add_plugins(ScreenshotPlugin)
            .add_systems(PostUpdate, export_frames);
    }
}

/// Switch to the menu's scenario `name`: it replaces the active one and the scene
/// restarts. An unknown name is refused with the valid ones and the scene runs on.
pub fn switch_scenario(world: &mut World, name: &str) -> Result<(), String> {
    let menu = world
        .get_resource::<ScenarioMenu>()
        .ok_or("this demo offers no other scenes")?;
    let active = menu.scenario(name).map_err(|e| e.to_string())?;
    world.insert_resource(active);
    reset(world);
    Ok(())
}

/// The shortcuts of [`UiKeys`] (by default space run/pause, R reset, E record frames,
/// = and − substeps).
fn shortcuts(
    keys: Res<ButtonInput<KeyCode>>,
    bindings: Res<UiKeys>,
    layout: Res<UiLayout>,
    mut step: ResMut<StrandsConfig>,
    mut collisions: ResMut<CollisionConfig>,
    mut metrics: ResMut<StrandMetrics>,
    mut commands: Commands,
) {
    if layout.keyboard_over_ui {
        return;
    }
    let pressed = |key: Option<KeyCode>| key.is_some_and(|k| keys.just_pressed(k));
    if pressed(bindings.pause) {
        step.paused = !step.paused;
    }
    if pressed(bindings.reset) {
        commands.queue(reset);
    }
    if pressed(bindings.record) && cfg!(not(target_arch = "wasm32")) {
        commands.queue(toggle_export);
    }
    // Within the range the panel and the page's commands accept.
    if pressed(bindings.more_substeps) && step.substeps < *SUBSTEPS_RANGE.end() {
        step.substeps += 1;
    }
    if pressed(bindings.fewer_substeps) && step.substeps > *SUBSTEPS_RANGE.start() {
        step.substeps -= 1;
    }
    // Crossings counted from when checking is switched on.
    if collisions.is_changed() && collisions.check_crossings && metrics.edge_crossings.is_none() {
        metrics.edge_crossings = Some(0);
    }
    if collisions.is_changed() && !collisions.check_crossings {
        metrics.edge_crossings = None;
    }
    let _ = &mut collisions;
}

/// Start the scene over: despawn everything it made, clear the figures, spawn it again.
pub fn reset(world: &mut World) {
    let mut doomed = world.query_filtered::<Entity, Or<(
        With<Particle>,
        With<Strand>,
        With<SpaghettiFactory>,
        With<MeatballFactory>,
        With<FurryCreature>,
    )>>();
    let doomed: Vec<Entity> = doomed.iter(world).collect();
    for entity in doomed {
        if let Ok(e) = world.get_entity_mut(entity) {
            e.despawn();
        }
    }
    *world.resource_mut::<SimulationClock>() = SimulationClock::default();
    let checked = world.resource::<CollisionConfig>().check_crossings;
    let mut metrics = world.resource_mut::<StrandMetrics>();
    metrics.reset_figures();
    metrics.edge_crossings = checked.then_some(0);
    world.resource_mut::<LengthErrorHistory>().samples.clear();
    world.resource_mut::<InputProblems>().clear();
    spawn_active_scenario(world);
}

#[cfg_attr(target_arch = "wasm32", allow(dead_code))]
fn toggle_export(world: &mut World) {
    let view = world
        .get_resource::<ActiveScenario>()
        .map(|a| a.scenario.view());
    let title = world
        .get_resource::<ActiveScenario>()
        .map_or("bevy_strands".to_string(), |a| a.scenario.name.clone());
    let mut export = world.resource_mut::<FrameExport>();
    if export.recorder.take().is_some() {
        return;
    }
    let Some(view) = view else {
        return;
    };
    let directory = export.directory.clone();
    match Recorder::new(
        FrameSettings::default(),
        view,
        &title,
        None,
        Some(&directory),
    ) {
        Ok(recorder) => {
            export.recorder = Some(recorder);
            export.message = None;
        }
        Err(e) => export.message = Some(e.to_string()),
    }
}

#[cfg_attr(target_arch = "wasm32", allow(dead_code))]
fn export_frames(world: &mut World) {
    let Some(mut recorder) = world.resource_mut::<FrameExport>().recorder.take() else {
        return;
    };
    match recorder.capture_if_due(world) {
        Ok(()) => world.resource_mut::<FrameExport>().recorder = Some(recorder),
        Err(e) => world.resource_mut::<FrameExport>().message = Some(e.to_string()),
    }
}

fn trim_history(mut history: ResMut<LengthErrorHistory>) {
    if history.samples.len() > PLOT_SAMPLES {
        let excess = history.samples.len() - PLOT_SAMPLES / 2;
        history.samples.drain(..excess);
    }
}

#[cfg(test)]
mod tests {
    use bevy::ecs::system::RunSystemOnce;

    use super::*;
    use crate::fixtures;

    /// Press `key` once and run the shortcuts; the substeps after.
    fn press(app: &mut App, key: KeyCode) -> u32 {
        let mut keys = ButtonInput::<KeyCode>::default();
        keys.press(key);
        app.insert_resource(keys);
        app.world_mut().run_system_once(shortcuts).unwrap();
        app.world().resource::<StrandsConfig>().substeps
    }

    #[test]
    fn the_substep_keys_stay_within_the_accepted_range() {
        let mut app = fixtures::app();
        app.init_resource::<UiKeys>().init_resource::<UiLayout>();
        app.world_mut().resource_mut::<StrandsConfig>().substeps = 499;
        assert_eq!(press(&mut app, KeyCode::Equal), 500);
        assert_eq!(press(&mut app, KeyCode::Equal), 500);
        app.world_mut().resource_mut::<StrandsConfig>().substeps = 2;
        assert_eq!(press(&mut app, KeyCode::Minus), 1);
        assert_eq!(press(&mut app, KeyCode::Minus), 1);
        // Space pauses and runs again.
        press(&mut app, KeyCode::Space);
        assert!(app.world().resource::<StrandsConfig>().paused);
        press(&mut app, KeyCode::Space);
        assert!(!app.world().resource::<StrandsConfig>().paused);
    }
}
