//! The built-in scenarios, compiled into the crate so the runner works from anywhere;
//! their text is the scenario file of the same name under the repository's
//! `assets/scenes/`.

use crate::scenario::{Scenario, ScenarioError};

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
        text: include_str!("../../assets/scenes/long_strand.ron"),
    },
    BuiltinScene {
        name: "spaghetti_factory",
        file: "assets/scenes/spaghetti_factory.ron",
        text: include_str!("../../assets/scenes/spaghetti_factory.ron"),
    },
    BuiltinScene {
        name: "meatball_factory",
        file: "assets/scenes/meatball_factory.ron",
        text: include_str!("../../assets/scenes/meatball_factory.ron"),
    },
    BuiltinScene {
        name: "furry_creature",
        file: "assets/scenes/furry_creature.ron",
        text: include_str!("../../assets/scenes/furry_creature.ron"),
    },
    BuiltinScene {
        name: "furry_creature_limp",
        file: "assets/scenes/furry_creature_limp.ron",
        text: include_str!("../../assets/scenes/furry_creature_limp.ron"),
    },
    BuiltinScene {
        name: "furry_creature_2000",
        file: "assets/scenes/furry_creature_2000.ron",
        text: include_str!("../../assets/scenes/furry_creature_2000.ron"),
    },
    BuiltinScene {
        name: "branches",
        file: "assets/scenes/branches.ron",
        text: include_str!("../../assets/scenes/branches.ron"),
    },
    BuiltinScene {
        name: "scale",
        file: "assets/scenes/scale.ron",
        text: include_str!("../../assets/scenes/scale.ron"),
    },
    BuiltinScene {
        name: "pile",
        file: "assets/scenes/pile.ron",
        text: include_str!("../../assets/scenes/pile.ron"),
    },
    BuiltinScene {
        name: "rope_coil",
        file: "assets/scenes/rope_coil.ron",
        text: include_str!("../../assets/scenes/rope_coil.ron"),
    },
    BuiltinScene {
        name: "whip",
        file: "assets/scenes/whip.ron",
        text: include_str!("../../assets/scenes/whip.ron"),
    },
    BuiltinScene {
        name: "pendulum_1e4",
        file: "assets/scenes/pendulum_1e4.ron",
        text: include_str!("../../assets/scenes/pendulum_1e4.ron"),
    },
    BuiltinScene {
        name: "pendulum_1e6",
        file: "assets/scenes/pendulum_1e6.ron",
        text: include_str!("../../assets/scenes/pendulum_1e6.ron"),
    },
    BuiltinScene {
        name: "sandbox",
        file: "assets/scenes/sandbox.ron",
        text: include_str!("../../assets/scenes/sandbox.ron"),
    },
    BuiltinScene {
        name: "rope_coil_fine",
        file: "assets/scenes/rope_coil_fine.ron",
        text: include_str!("../../assets/scenes/rope_coil_fine.ron"),
    },
    BuiltinScene {
        name: "pile_fine",
        file: "assets/scenes/pile_fine.ron",
        text: include_str!("../../assets/scenes/pile_fine.ron"),
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
