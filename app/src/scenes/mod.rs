//! The scenario logic that runs during a simulation: the spaghetti and meatball
//! factories, the drain that bounds their pile and the furry creature, each with the spec a scenario file gives it.

pub mod drain;
pub mod furry_creature;
pub mod meatball_factory;
pub mod spaghetti_factory;

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::forces::plugin::apply_tethers;
use bevy_strands::schedule::{StepSet, StrandsStep, StrandsTick, TickSet};

use drain::{Drain, run_drains};
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
            .register_type::<Drain>()
            .register_type::<FurryCreature>()
            .register_type::<Disc>()
            .add_systems(
                StrandsTick,
                (run_spaghetti_factories, run_meatball_factories, run_drains)
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
