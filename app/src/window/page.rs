//! The demo inside a web page (the `web` example): which scene the page asks for, and
//! the live figures handed to the page. On wasm32 with the `web` feature the figures are
//! written each frame as JSON into the page's `#strands-figures` element, where the
//! visitor reads them and a browser test parses them; elsewhere they are only computed.

use bevy::diagnostic::FrameCount;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use serde::Serialize;

use super::ActiveScenario;
use super::pace::RealTimeFactor;
use super::tools::ToolState;

/// The id of the page element the figures are written into.
pub const FIGURES_ELEMENT: &str = "strands-figures";

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

/// Hands the figures to the page each frame.
pub struct PageFiguresPlugin;

impl Plugin for PageFiguresPlugin {
    fn build(&self, app: &mut App) {
        #[cfg(all(feature = "web", target_arch = "wasm32"))]
        app.add_systems(Last, write_figures);
        let _ = app;
    }
}

#[cfg(all(feature = "web", target_arch = "wasm32"))]
fn write_figures(world: &mut World) {
    let json = PageFigures::read(world).to_json();
    let element = web_sys::window()
        .and_then(|w| w.document())
        .and_then(|d| d.get_element_by_id(FIGURES_ELEMENT));
    // A page without the element shows no figures; the demo runs on.
    if let Some(element) = element {
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
