//! The web page's controls as text commands, one a line: what the page's buttons and
//! menus write into its `#strands-commands` element and the app carries out at the
//! start of the next frame (see [`super::page`]). Parsing and carrying out are plain
//! functions, tested without a browser.

use std::ops::RangeInclusive;

use bevy::prelude::*;
use bevy_strands::prelude::*;

use super::controls::{reset, switch_scenario};
use super::tools::{Tool, ToolState};

/// The step sizes the controls accept, in seconds (the panel's range too).
pub const DT_RANGE: RangeInclusive<f64> = 1e-5..=1e-1;
/// The substeps per tick the controls accept (the panel's range too).
pub const SUBSTEPS_RANGE: RangeInclusive<u32> = 1..=500;

/// One command of the page's controls.
#[derive(Clone, Debug, PartialEq)]
pub enum PageCommand {
    /// `pause`: stop the clock.
    Pause,
    /// `run`: start it again.
    Run,
    /// `step`: one tick, then paused.
    Step,
    /// `reset`: start the scene over.
    Reset,
    /// `scene NAME`: switch to another of the demo's scenes.
    Scene(String),
    /// `tool NAME`: pick a mouse tool by its panel name (`drag`, `pin`, …).
    Tool(Tool),
    /// `dt SECONDS`: the step size.
    Dt(f64),
    /// `substeps N`: steps per tick.
    Substeps(u32),
}

impl PageCommand {
    /// A command from one line; a line that is not one says why, with what is valid.
    pub fn parse(line: &str) -> Result<Self, String> {
        let mut words = line.split_whitespace();
        let verb = words.next().ok_or("an empty command")?;
        let argument = words.next();
        if words.next().is_some() {
            return Err(format!("{line:?}: one argument at most"));
        }
        let needs = |what: &str| argument.ok_or(format!("{verb:?} needs {what}"));
        let command = match verb {
            "pause" => Self::Pause,
            "run" => Self::Run,
            "step" => Self::Step,
            "reset" => Self::Reset,
            "scene" => Self::Scene(needs("a scene's name")?.to_string()),
            "tool" => {
                let name = needs("a tool's name")?;
                let tool = Tool::ALL.into_iter().find(|t| t.label() == name);
                Self::Tool(tool.ok_or_else(|| {
                    let names: Vec<&str> = Tool::ALL.iter().map(|t| t.label()).collect();
                    format!("no tool {name:?}; valid: {}", names.join(", "))
                })?)
            }
            "dt" => {
                let text = needs("a step in seconds")?;
                let dt = text
                    .parse()
                    .map_err(|_| format!("dt {text:?}: not a number"))?;
                Self::Dt(within("dt", dt, &DT_RANGE)?)
            }
            "substeps" => {
                let text = needs("a count")?;
                let n = (text.parse()).map_err(|_| format!("substeps {text:?}: not a count"))?;
                Self::Substeps(within("substeps", n, &SUBSTEPS_RANGE)?)
            }
            _ => {
                return Err(format!(
                    "no command {verb:?}; valid: pause, run, step, reset, scene NAME, \
                     tool NAME, dt SECONDS, substeps N"
                ));
            }
        };
        if argument.is_some()
            && matches!(command, Self::Pause | Self::Run | Self::Step | Self::Reset)
        {
            return Err(format!("{verb:?} takes no argument"));
        }
        Ok(command)
    }

    /// Carry the command out; one that cannot be (an unknown scene) changes nothing.
    pub fn apply(&self, world: &mut World) -> Result<(), String> {
        match self {
            Self::Pause | Self::Run => {
                let paused = *self == Self::Pause;
                let mut config = world.resource_mut::<StrandsConfig>();
                // Written only when it changes: a change of the configuration
                // rebuilds caches.
                if config.paused != paused {
                    config.paused = paused;
                }
            }
            Self::Step => {
                world.resource_mut::<StrandsConfig>().paused = true;
                world.run_schedule(StrandsTick);
            }
            Self::Reset => reset(world),
            Self::Scene(name) => switch_scenario(world, name)?,
            Self::Tool(tool) => {
                let mut tools = world.get_resource_or_init::<ToolState>();
                tools.tool = *tool;
                tools.message = None;
            }
            Self::Dt(dt) => world.resource_mut::<StrandsConfig>().dt = *dt,
            Self::Substeps(n) => world.resource_mut::<StrandsConfig>().substeps = *n,
        }
        Ok(())
    }
}

/// `value` if `range` holds it, or why not (NaN is outside every range).
fn within<T: PartialOrd + std::fmt::Display>(
    what: &str,
    value: T,
    range: &RangeInclusive<T>,
) -> Result<T, String> {
    if range.contains(&value) {
        Ok(value)
    } else {
        Err(format!(
            "{what} {value}: outside {} to {}",
            range.start(),
            range.end()
        ))
    }
}

/// Carry out each line of `text`; the errors of the lines that fail, in order (the
/// others are carried out all the same).
pub fn run_commands(world: &mut World, text: &str) -> Vec<String> {
    (text.lines().filter(|line| !line.trim().is_empty()))
        .filter_map(|line| {
            PageCommand::parse(line)
                .and_then(|command| command.apply(world))
                .err()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use bevy_strands::metrics::LengthErrorHistory;

    use super::*;
    use crate::fixtures;
    use crate::window::{ScenarioMenu, spawn_active_scenario};

    /// A headless demo: the menu's first scene spawned, as the page starts it.
    fn demo() -> App {
        let mut app = fixtures::app();
        let menu = ScenarioMenu::builtin(&["long_strand", "meatball_factory"]).unwrap();
        let active = menu.scenario("long_strand").unwrap();
        app.insert_resource(menu)
            .insert_resource(active)
            .init_resource::<LengthErrorHistory>()
            .init_resource::<ToolState>();
        spawn_active_scenario(app.world_mut());
        app
    }

    fn scene(app: &App) -> String {
        let active = app.world().resource::<crate::window::ActiveScenario>();
        active.scenario.name.clone()
    }

    #[test]
    fn every_command_reads_and_bad_ones_say_why() {
        use PageCommand::*;
        assert_eq!(PageCommand::parse("pause"), Ok(Pause));
        assert_eq!(PageCommand::parse(" run "), Ok(Run));
        assert_eq!(PageCommand::parse("tool pin"), Ok(Tool(super::Tool::Pin)));
        assert_eq!(PageCommand::parse("dt 0.0025"), Ok(Dt(0.0025)));
        assert_eq!(PageCommand::parse("substeps 30"), Ok(Substeps(30)));
        assert_eq!(
            PageCommand::parse("scene meatball_factory"),
            Ok(Scene("meatball_factory".into()))
        );
        for (line, says) in [
            ("", "empty"),
            ("jump", "valid: pause"),
            ("tool lasso", "valid: drag, particle"),
            ("dt", "needs a step"),
            ("dt fast", "not a number"),
            ("dt NaN", "outside"),
            ("dt 0", "outside"),
            ("dt inf", "outside"),
            ("substeps 0", "outside"),
            ("substeps -3", "not a count"),
            ("pause now", "takes no argument"),
            ("scene a b", "one argument"),
        ] {
            let error = PageCommand::parse(line).unwrap_err();
            assert!(error.contains(says), "{line:?} gave {error:?}");
        }
    }

    #[test]
    fn commands_pause_step_and_run_the_clock() {
        let mut app = demo();
        assert!(run_commands(app.world_mut(), "pause\n").is_empty());
        assert!(app.world().resource::<StrandsConfig>().paused);
        let substeps = app.world().resource::<StrandsConfig>().substeps as u64;
        assert!(run_commands(app.world_mut(), "step\nstep").is_empty());
        // Two ticks taken while paused, and it stays paused.
        assert_eq!(
            app.world().resource::<SimulationClock>().steps,
            2 * substeps
        );
        assert!(app.world().resource::<StrandsConfig>().paused);
        assert!(run_commands(app.world_mut(), "run").is_empty());
        assert!(!app.world().resource::<StrandsConfig>().paused);
    }

    #[test]
    fn commands_set_the_step_and_the_tool_and_a_bad_line_changes_nothing() {
        let mut app = demo();
        let before = app.world().resource::<StrandsConfig>().clone();
        let errors = run_commands(
            app.world_mut(),
            "dt 0.002\nsubsteps 0\ntool hair\nsubsteps 4",
        );
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert!(errors[0].contains("substeps 0"));
        let config = app.world().resource::<StrandsConfig>();
        assert_eq!((config.dt, config.substeps), (0.002, 4));
        assert_eq!(config.gravity, before.gravity);
        assert_eq!(app.world().resource::<ToolState>().tool, Tool::Hair);
    }

    #[test]
    fn a_scene_command_switches_the_scene_and_an_unknown_one_keeps_it() {
        let mut app = demo();
        for _ in 0..3 {
            run_commands(app.world_mut(), "step");
        }
        let particles = |app: &mut App| {
            let mut query = app.world_mut().query::<&Particle>();
            query.iter(app.world()).count()
        };
        let (rope, steps) = (
            particles(&mut app),
            app.world().resource::<SimulationClock>().steps,
        );
        assert!(rope > 0 && steps > 0);
        let errors = run_commands(app.world_mut(), "scene spaghetti_factory");
        assert!(
            errors[0].contains("valid: long_strand, meatball_factory"),
            "{errors:?}"
        );
        assert_eq!(scene(&app), "long_strand");
        assert_eq!(particles(&mut app), rope);
        assert_eq!(app.world().resource::<SimulationClock>().steps, steps);
        assert!(run_commands(app.world_mut(), "scene meatball_factory").is_empty());
        assert_eq!(scene(&app), "meatball_factory");
        // Started over: the clock back at zero and the rope gone.
        assert_eq!(app.world().resource::<SimulationClock>().steps, 0);
        assert_ne!(particles(&mut app), rope);
        assert!(run_commands(app.world_mut(), "reset").is_empty());
        assert_eq!(scene(&app), "meatball_factory");
    }
}
