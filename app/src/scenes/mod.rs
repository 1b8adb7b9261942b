//! The built-in scenarios, compiled into the crate so the runner works from anywhere
//! (their text is the scenario file under the repository's `assets/scenes/`), and the
//! scenario logic that runs during a simulation (the factories, the furry creature).

pub mod furry_creature;
pub mod meatball_factory;
pub mod spaghetti_factory;

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::forces::plugin::apply_tethers;
use bevy_strands::schedule::{StepSet, StrandsStep, StrandsTick, TickSet};

use crate::scenario::{Scenario, ScenarioError};
use furry_creature::{FurryCreature, drive_furry_creatures};
use meatball_factory::{MeatballFactory, run_meatball_factories};
use spaghetti_factory::{SpaghettiFactory, run_spaghetti_factories};

/// A disc drawn under the strands (a furry creature's body).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct Disc {
    /// Centre.
    pub centre: DVec2,
    /// Radius.
    pub radius: f64,
}

/// Scenario logic: factories and other scripted sources.
pub struct ScenesPlugin;

impl Plugin for ScenesPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<SpaghettiFactory>()
            .register_type::<MeatballFactory>()
            .register_type::<FurryCreature>()
            .register_type::<Disc>()
            .add_systems(
                StrandsTick,
                (run_spaghetti_factories, run_meatball_factories)
                    .chain()
                    .in_set(TickSet::Prepare),
            )
            .add_systems(
                StrandsStep,
                drive_furry_creatures
                    .in_set(StepSet::Forces)
                    .after(apply_tethers),
            );
    }
}

/// A scenario shipped with the crate.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// Name, as given to `strands run`.
    pub name: &'static str,
    /// Path of its scene file in the repository.
    pub file: &'static str,
    /// The scene file's text.
    pub text: &'static str,
}

impl BuiltinScene {
    /// Parse and validate the scenario.
    pub fn scenario(&self) -> Result<Scenario, ScenarioError> {
        Scenario::parse(self.text, self.file)
    }
}

/// Every built-in scenario.
pub const BUILTIN_SCENES: &[BuiltinScene] = &[
    BuiltinScene {
        name: "long_strand",
        file: "assets/scenes/long_strand.ron",
        text: include_str!("../../../assets/scenes/long_strand.ron"),
    },
    BuiltinScene {
        name: "spaghetti_factory",
        file: "assets/scenes/spaghetti_factory.ron",
        text: include_str!("../../../assets/scenes/spaghetti_factory.ron"),
    },
    BuiltinScene {
        name: "meatball_factory",
        file: "assets/scenes/meatball_factory.ron",
        text: include_str!("../../../assets/scenes/meatball_factory.ron"),
    },
    BuiltinScene {
        name: "furry_creature",
        file: "assets/scenes/furry_creature.ron",
        text: include_str!("../../../assets/scenes/furry_creature.ron"),
    },
    BuiltinScene {
        name: "branches",
        file: "assets/scenes/branches.ron",
        text: include_str!("../../../assets/scenes/branches.ron"),
    },
    BuiltinScene {
        name: "scale",
        file: "assets/scenes/scale.ron",
        text: include_str!("../../../assets/scenes/scale.ron"),
    },
    BuiltinScene {
        name: "sandbox",
        file: "assets/scenes/sandbox.ron",
        text: include_str!("../../../assets/scenes/sandbox.ron"),
    },
];

/// The built-in scenario called `name`.
pub fn builtin(name: &str) -> Option<&'static BuiltinScene> {
    BUILTIN_SCENES.iter().find(|s| s.name == name)
}

/// The names of the built-in scenarios.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN_SCENES.iter().map(|s| s.name).collect()
}
