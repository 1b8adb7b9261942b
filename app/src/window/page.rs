//! The demo inside a web page (the `web` example): which scene the page asks for, the
//! live figures handed to the page, and the commands its controls send. On wasm32 with
//! the `web` feature the figures are written each frame as JSON into the page's
//! `#strands-figures` element, where the page's panel shows them and a browser test
//! parses them, and the lines the page's buttons write into `#strands-commands` are
//! carried out (see [`super::command`]); elsewhere the figures are only computed.

use bevy::diagnostic::FrameCount;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use serde::Serialize;

#[cfg(all(feature = "web", target_arch = "wasm32"))]
use super::command::run_commands;
use super::pace::RealTimeFactor;
use super::tools::ToolState;
use super::{ActiveScenario, ScenarioMenu};

/// The id of the page element the figures are written into.
pub const FIGURES_ELEMENT: &str = "strands-figures";
/// The id of the page element its controls write their commands into, one a line.
pub const COMMANDS_ELEMENT: &str = "strands-commands";

/// The last command of the page's that could not be carried out, and why.
#[derive(Resource, Clone, Debug, Default)]
pub struct PageCommandError(pub Option<String>);

/// What the page shows and a test reads: the panel's main figures.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct PageFigures {
    /// The scenario's name.
    pub scene: String,
    /// Simulated seconds.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    /// Particles now.
    pub particles: usize,
    /// Strands now.
    pub strands: usize,
    /// The largest relative length error of any edge since the start.
    pub max_rel_length_error: f64,
    /// Edge crossings seen, if the check runs.
    pub edge_crossings: Option<u64>,
    /// Simulated over wall-clock seconds, once measured.
    pub real_time_factor: Option<f64>,
    /// Frames drawn.
    pub frames: u32,
    /// Whether the clock is stopped.
    pub paused: bool,
    /// The step size, in seconds.
    pub dt: f64,
    /// Steps per tick.
    pub substeps: u32,
    /// The mouse tool's name.
    pub tool: String,
    /// The scenes the page may switch to.
    pub scenes: Vec<String>,
    /// Why the last command that failed did, or why the last tool use failed.
    pub message: Option<String>,
    /// The pointer's world position, when it is over the scene's window.
    pub cursor: Option<[f64; 2]>,
    /// Whether a particle is under the pointer (what a press would grab).
    pub hovering: bool,
    /// Whether the mouse is dragging a particle.
    pub dragging: bool,
    /// Whether every figure above is finite (JSON writes a non-finite number as null).
    pub finite: bool,
}

impl PageFigures {
    /// The figures of the world as it is.
    pub fn read(world: &World) -> Self {
        let metrics = world.resource::<StrandMetrics>();
        let clock = world.resource::<SimulationClock>();
        let real_time_factor = world.get_resource::<RealTimeFactor>().and_then(|r| r.value);
        let tools = world.get_resource::<ToolState>();
        let config = world.resource::<StrandsConfig>();
        let command_error = world.get_resource::<PageCommandError>();
        let message = (command_error.and_then(|e| e.0.clone()))
            .or_else(|| tools.and_then(|t| t.message.clone()));
        let finite = clock.time.is_finite()
            && metrics.max_rel_length_error.is_finite()
            && real_time_factor.is_none_or(f64::is_finite);
        Self {
            scene: (world.get_resource::<ActiveScenario>())
                .map_or(String::new(), |a| a.scenario.name.clone()),
            time: clock.time,
            steps: clock.steps,
            particles: metrics.particles,
            strands: metrics.strands,
            max_rel_length_error: metrics.max_rel_length_error,
            edge_crossings: metrics.edge_crossings,
            real_time_factor,
            frames: world.get_resource::<FrameCount>().map_or(0, |f| f.0),
            paused: config.paused,
            dt: config.dt,
            substeps: config.substeps,
            tool: tools.map_or("drag", |t| t.tool.label()).to_string(),
            scenes: (world.get_resource::<ScenarioMenu>()).map_or(Vec::new(), |m| m.names.clone()),
            message,
            cursor: tools.and_then(|t| t.cursor).map(|c| c.to_array()),
            hovering: tools.is_some_and(|t| t.hovered.is_some()),
            dragging: tools.is_some_and(|t| t.dragging().is_some()),
            finite,
        }
    }

    /// The figures as one line of JSON.
    pub fn to_json(&self) -> String {
        // Plain numbers, strings and options: serializing cannot fail.
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// The scene a visitor asked for: `?scene=NAME` in the page's address on the web, the
/// first command-line argument elsewhere.
pub fn requested_scene() -> Option<String> {
    #[cfg(all(feature = "web", target_arch = "wasm32"))]
    {
        let search = web_sys::window()?.location().search().ok()?;
        scene_in_query(&search)
    }
    #[cfg(not(all(feature = "web", target_arch = "wasm32")))]
    {
        std::env::args().nth(1)
    }
}

/// `NAME` from a query string such as `?scene=NAME&x=1`.
pub fn scene_in_query(search: &str) -> Option<String> {
    (search.trim_start_matches('?').split('&'))
        .find_map(|pair| pair.strip_prefix("scene="))
        .filter(|name| !name.is_empty())
        .map(str::to_string)
}

/// Hands the figures to the page each frame, and carries out its controls' commands.
pub struct PageFiguresPlugin;

impl Plugin for PageFiguresPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<PageCommandError>();
        #[cfg(all(feature = "web", target_arch = "wasm32"))]
        app.add_systems(First, read_commands)
            .add_systems(Last, write_figures);
    }
}

/// The page's element of id `id`, if the page has one.
#[cfg(all(feature = "web", target_arch = "wasm32"))]
fn element(id: &str) -> Option<web_sys::Element> {
    web_sys::window()?.document()?.get_element_by_id(id)
}

/// Take the lines the page's controls wrote since the last frame and carry them out.
#[cfg(all(feature = "web", target_arch = "wasm32"))]
fn read_commands(world: &mut World) {
    let Some(element) = element(COMMANDS_ELEMENT) else {
        return;
    };
    let Some(text) = element.text_content().filter(|t| !t.trim().is_empty()) else {
        return;
    };
    element.set_text_content(None);
    let errors = run_commands(world, &text);
    for e in &errors {
        warn!("bevy_strands: the page's command failed: {e}");
    }
    // The newest failure shows until a later command succeeds.
    world.resource_mut::<PageCommandError>().0 = errors.last().cloned();
}

#[cfg(all(feature = "web", target_arch = "wasm32"))]
fn write_figures(world: &mut World) {
    let json = PageFigures::read(world).to_json();
    // A page without the element shows no figures; the demo runs on.
    if let Some(element) = element(FIGURES_ELEMENT) {
        element.set_text_content(Some(&json));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_is_read_from_the_query() {
        assert_eq!(
            scene_in_query("?scene=meatball_factory"),
            Some("meatball_factory".into())
        );
        assert_eq!(
            scene_in_query("?x=1&scene=long_strand"),
            Some("long_strand".into())
        );
        assert_eq!(scene_in_query("?scene="), None);
        assert_eq!(scene_in_query(""), None);
    }

    #[test]
    fn figures_say_when_a_number_is_not_finite() {
        let mut world = World::new();
        world.init_resource::<StrandMetrics>();
        world.init_resource::<SimulationClock>();
        world.init_resource::<StrandsConfig>();
        world.resource_mut::<SimulationClock>().time = 1.5;
        let figures = PageFigures::read(&world);
        assert!(figures.finite);
        assert!(figures.to_json().contains("\"time\":1.5"));
        world.resource_mut::<StrandMetrics>().max_rel_length_error = f64::NAN;
        let figures = PageFigures::read(&world);
        assert!(!figures.finite);
        assert!(figures.to_json().contains("\"max_rel_length_error\":null"));
    }
}
