//! Configuration of the time step and the forces.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::strand::StrandMaterial;

/// Step size, substeps and the global force parameters.
///
/// Each fixed tick runs `substeps` steps of `dt` seconds (DESIGN §4). The defaults are
/// the canonical scenes': 30 steps of 1/3000 s per 1/100 s tick.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_strands::prelude::*;
/// let mut app = App::new();
/// app.add_plugins(StrandsPlugin::manual());
/// let mut config = app.world_mut().resource_mut::<StrandsConfig>();
/// config.dt = 1.0 / 60.0;
/// config.substeps = 1;
/// ```
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[reflect(Resource)]
pub struct StrandsConfig {
    /// Step size in seconds.
    pub dt: f64,
    /// Steps per fixed tick.
    pub substeps: u32,
    /// Gravity acceleration.
    pub gravity: DVec2,
    /// Mass-proportional damping coefficient (1/s): `f = −c m v`.
    pub damping: f64,
    /// Material of strands that carry no [`StrandMaterial`] of their own.
    pub material: StrandMaterial,
    /// Whether ticks advance the simulation. A paused simulation keeps its state.
    pub paused: bool,
}

impl Default for StrandsConfig {
    fn default() -> Self {
        Self {
            dt: 1.0 / 3000.0,
            substeps: 30,
            gravity: DVec2::new(0.0, -9.81),
            damping: 0.0,
            material: StrandMaterial::default(),
            paused: false,
        }
    }
}

impl StrandsConfig {
    /// Simulated seconds per fixed tick.
    pub fn tick_seconds(&self) -> f64 {
        self.dt * self.substeps as f64
    }
}
