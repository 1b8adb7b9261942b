//! # bevy_strands
//!
//! 2D strands — spaghetti, ropes, hair — whose edges never stretch, as a Bevy plugin.
//!
//! Particles are entities with [`Position`](particle::Position),
//! [`Velocity`](particle::Velocity) and [`Mass`](particle::Mass); a strand is an entity
//! whose [`Strand`](strand::Strand) lists its particles in order. Each fixed tick runs
//! `substeps` steps through the stages of [`StepSet`](schedule::StepSet).
//!
//! ```
//! use bevy::prelude::*;
//! use bevy::math::DVec2;
//! use bevy_strands::prelude::*;
//!
//! let mut app = App::new();
//! app.add_plugins((MinimalPlugins, StrandsPlugin::manual()));
//! // A rope of 20 particles hanging from a pinned end.
//! let rope = StrandBuilder::line(DVec2::new(0.5, 0.9), DVec2::X, 20, 0.02)
//!     .pin_first()
//!     .spawn_in(app.world_mut())
//!     .unwrap();
//! // One tick: 30 steps of 1/3000 s.
//! app.world_mut().run_schedule(StrandsTick);
//! assert_eq!(app.world().resource::<SimulationClock>().steps, 30);
//! # let _ = rope;
//! ```

pub mod collision;
pub mod config;
pub mod constraints;
pub mod export;
pub mod forces;
pub mod integrate;
pub mod metrics;
pub mod particle;
#[cfg(feature = "render")]
pub mod render;
pub mod report;
pub mod runner;
pub mod scene;
pub mod scenes;
pub mod schedule;
pub mod state;
pub mod strand;
pub mod tools;
pub mod topology;

use bevy::app::PluginGroupBuilder;
use bevy::ecs::schedule::{InternedScheduleLabel, ScheduleLabel};
use bevy::prelude::*;

use collision::CollisionPlugin;
use config::StrandsConfig;
use constraints::ConstraintsPlugin;
use metrics::StrandMetrics;
use scenes::ScenesPlugin;
use schedule::{SchedulePlugin, SimulationClock};
use state::ParticleState;
use topology::{InputProblems, Topology};

/// Everything most users need.
pub mod prelude {
    pub use crate::collision::{CollisionConfig, CollisionPlugin};
    pub use crate::config::StrandsConfig;
    pub use crate::constraints::{ConstraintConfig, ConstraintsPlugin, SolverKind};
    pub use crate::metrics::StrandMetrics;
    pub use crate::particle::{ExternalForce, Mass, Particle, Pinned, Position, Velocity};
    pub use crate::schedule::{SimulationClock, StepSet, StrandsStep, StrandsTick, TickSet};
    pub use crate::state::ParticleState;
    pub use crate::strand::{Strand, StrandBuilder, StrandKind, StrandMaterial, StrandOf};
    pub use crate::topology::{InputProblems, Topology};
    pub use crate::{StrandsCorePlugin, StrandsPlugin};
}

/// The simulation: all of this crate's plugins.
///
/// By default a tick runs in [`FixedUpdate`], and the fixed timestep follows
/// [`StrandsConfig::tick_seconds`]. [`StrandsPlugin::manual`] leaves the driving to the
/// caller (`world.run_schedule(StrandsTick)`), as headless runs and tests do.
#[derive(Clone, Debug)]
pub struct StrandsPlugin {
    /// The schedule that runs a tick; `None` to drive by hand.
    pub driver: Option<InternedScheduleLabel>,
}

impl Default for StrandsPlugin {
    fn default() -> Self {
        Self::new(FixedUpdate)
    }
}

impl StrandsPlugin {
    /// Run one tick each time `schedule` runs.
    pub fn new(schedule: impl ScheduleLabel) -> Self {
        Self {
            driver: Some(schedule.intern()),
        }
    }

    /// Never tick on its own: the caller runs [`StrandsTick`](schedule::StrandsTick).
    pub fn manual() -> Self {
        Self { driver: None }
    }
}

impl PluginGroup for StrandsPlugin {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(StrandsCorePlugin {
                driver: self.driver,
            })
            .add(ConstraintsPlugin)
            .add(CollisionPlugin)
            .add(ScenesPlugin)
    }
}

/// Particles, strands, the step schedule, forces, integration and metrics.
#[derive(Clone, Debug)]
pub struct StrandsCorePlugin {
    /// The schedule that runs a tick; `None` to drive by hand.
    pub driver: Option<InternedScheduleLabel>,
}

impl Plugin for StrandsCorePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<StrandsConfig>()
            .init_resource::<ParticleState>()
            .init_resource::<Topology>()
            .init_resource::<InputProblems>()
            .init_resource::<SimulationClock>()
            .init_resource::<StrandMetrics>()
            .register_type::<StrandsConfig>()
            .register_type::<SimulationClock>()
            .register_type::<particle::Particle>()
            .register_type::<particle::Position>()
            .register_type::<particle::Velocity>()
            .register_type::<particle::Mass>()
            .register_type::<particle::Pinned>()
            .register_type::<particle::ExternalForce>()
            .register_type::<strand::Strand>()
            .register_type::<strand::StrandMaterial>()
            .register_type::<strand::StrandKind>()
            .register_type::<forces::tether::Tether>()
            .add_plugins(SchedulePlugin {
                driver: self.driver,
            });
    }
}
