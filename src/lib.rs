//! # bevy_strands
//!
//! 2D strands — spaghetti, ropes, hair — whose edges never stretch, as a Bevy plugin.
//!
//! Particles are entities with [`Position`](world::particle::Position),
//! [`Velocity`](world::particle::Velocity) and [`Mass`](world::particle::Mass); a strand
//! is an entity whose [`Strand`](world::strand::Strand) lists its particles in order.
//! Each fixed tick runs `substeps` steps through the stages of
//! [`StepSet`](schedule::StepSet); `schedule.rs` is the one place that fixes their order.
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
//! // One tick: 6 steps of 1/600 s.
//! app.world_mut().run_schedule(StrandsTick);
//! assert_eq!(app.world().resource::<SimulationClock>().steps, 6);
//! # let _ = rope;
//! ```
//!
//! The layers, bottom up: [`model`] (plain data and rules) and [`linalg`] (solvers with
//! no physics), the kernels in [`forces`], [`constraints`] (the edges), [`collision`]
//! and [`contact`] (the contact solve) (slices in, slices out), the ECS layer in
//! [`world`], and the systems and plugins on top ([`schedule`], each area's `plugin`,
//! [`metrics`]). The repository's `docs/ARCHITECTURE.md` walks through
//! them.

#![warn(missing_docs)]

pub mod anchors;
#[cfg(feature = "avian")]
pub mod avian;
#[cfg(any(feature = "avian", feature = "rapier"))]
pub mod bodies;
pub mod colliders;
pub mod collision;
pub mod constraints;
pub mod contact;
pub mod contact_events;
pub mod forces;
pub mod guard;
pub mod halving;
pub mod integrate;
pub mod linalg;
pub mod metrics;
pub mod model;
pub mod parallel;
#[cfg(feature = "rapier")]
pub mod rapier;
#[cfg(feature = "render")]
pub mod render;
pub mod ribbon;
pub mod schedule;
pub mod sleeping;
pub mod snapshot;
pub mod split_ahead;
pub mod tearing;
pub mod transforms;
pub mod winch;
pub mod world;

use bevy::app::PluginGroupBuilder;
use bevy::ecs::schedule::{InternedScheduleLabel, ScheduleLabel};
use bevy::prelude::*;

use collision::CollisionPlugin;
use constraints::ConstraintsPlugin;
use contact::ContactLoopPlugin;
use forces::ForcesPlugin;
use integrate::IntegratorPlugin;
use metrics::MetricsPlugin;
use schedule::{SchedulePlugin, StrandsTick, TickSet};
use world::clock::SimulationClock;
use world::config::{CollisionConfig, LengthUnit, StrandsConfig};
use world::hooks::{SpawnOrder, TopologyDirty};
use world::problems::InputProblems;
use world::state::ParticleState;
use world::sync::{gather, write_back};
use world::topology::{Topology, detect_strand_edits, rebuild_topology, topology_dirty};

/// Everything most users need.
pub mod prelude {
    pub use crate::anchors::Anchor;
    #[cfg(feature = "avian")]
    pub use crate::avian::StrandsAvianPlugin;
    #[cfg(any(feature = "avian", feature = "rapier"))]
    pub use crate::bodies::{BodyAnchor, BodyView, CollidesWithStrands};
    pub use crate::colliders::{ColliderShape, StrandCollider};
    pub use crate::collision::CollisionPlugin;
    pub use crate::constraints::{ConstraintsPlugin, SolverKind};
    pub use crate::contact::ContactSolver;
    pub use crate::contact_events::StrandContact;
    pub use crate::guard::{FiniteGuard, NonFiniteState};
    pub use crate::metrics::StrandMetrics;
    #[cfg(feature = "rapier")]
    pub use crate::rapier::StrandsRapierPlugin;
    pub use crate::schedule::{
        CollideSet, StepSet, StrandsStep, StrandsSystems, StrandsTick, TickSet,
    };
    pub use crate::tearing::{StrandTorn, Tearable};
    pub use crate::transforms::{SyncTransform, TickPositions};
    pub use crate::winch::Winch;
    pub use crate::world::builder::StrandBuilder;
    pub use crate::world::clock::SimulationClock;
    pub use crate::world::config::{
        BendingModel, CollisionConfig, ConstraintConfig, ContactConfig, LengthUnit, SleepConfig,
        StrandsConfig,
    };
    pub use crate::world::particle::{
        ExternalForce, Frozen, Kinematic, Mass, Particle, Pinned, Position, Sleeping, Tether,
        Velocity,
    };
    pub use crate::world::problems::InputProblems;
    pub use crate::world::state::ParticleState;
    pub use crate::world::strand::{Strand, StrandKind, StrandMaterial, StrandOf};
    pub use crate::world::topology::Topology;
    pub use crate::{StrandsCorePlugin, StrandsPlugin};
}

/// The simulation: all of this crate's plugins.
///
/// By default a tick runs in [`FixedPostUpdate`] (after the game's own fixed-step
/// systems, as avian does), inside [`StrandsSystems`](schedule::StrandsSystems), and
/// covers that schedule's delta in [`StrandsConfig::substeps`] steps. The app's
/// `Time<Fixed>` is the game's: the plugin never changes it. [`StrandsPlugin::manual`]
/// leaves the driving to the caller (`world.run_schedule(StrandsTick)`), as headless
/// runs and tests do; the step is then [`StrandsConfig::dt`].
///
/// ```
/// use bevy::math::DVec2;
/// use bevy::prelude::*;
/// use bevy_strands::prelude::*;
///
/// // In a game: a tick each fixed update, in a world drawn 100 pixels a metre.
/// let mut game = App::new();
/// game.add_plugins((MinimalPlugins, StrandsPlugin::default().with_length_unit(100.0)));
///
/// // In a test: ticks run by hand.
/// let mut app = App::new();
/// app.add_plugins((MinimalPlugins, StrandsPlugin::manual()));
/// app.finish();
/// app.cleanup();
/// let rope = StrandBuilder::line(DVec2::new(0.0, 1.0), DVec2::X, 10, 0.05)
///     .pin_first()
///     .spawn_in(app.world_mut())
///     .unwrap();
/// for _ in 0..20 {
///     app.world_mut().run_schedule(StrandsTick);
/// }
/// // A fifth of a second on, the free end has swung down; every edge kept its length.
/// let end = *app.world().get::<Strand>(rope).unwrap().particles.last().unwrap();
/// assert!(app.world().get::<Position>(end).unwrap().0.y < 0.9);
/// assert!(app.world().resource::<StrandMetrics>().max_rel_length_error < 1e-9);
/// ```
#[derive(Clone, Debug)]
pub struct StrandsPlugin {
    /// The schedule that runs a tick; `None` to drive by hand.
    pub driver: Option<InternedScheduleLabel>,
    /// World units per metre ([`LengthUnit`]).
    pub length_unit: f64,
}

impl Default for StrandsPlugin {
    fn default() -> Self {
        Self::new(FixedPostUpdate)
    }
}

impl StrandsPlugin {
    /// Run one tick each time `schedule` runs.
    pub fn new(schedule: impl ScheduleLabel) -> Self {
        Self {
            driver: Some(schedule.intern()),
            length_unit: 1.0,
        }
    }

    /// Never tick on its own: the caller runs [`StrandsTick`].
    pub fn manual() -> Self {
        Self {
            driver: None,
            length_unit: 1.0,
        }
    }

    /// A world of `unit` world units per metre (100 for 100 pixels a metre): the
    /// defaults that carry a length are scaled ([`LengthUnit`]).
    pub fn with_length_unit(mut self, unit: f64) -> Self {
        self.length_unit = unit;
        self
    }
}

impl PluginGroup for StrandsPlugin {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(StrandsCorePlugin {
                driver: self.driver,
                length_unit: self.length_unit,
            })
            .add(halving::HalvingPlugin)
            .add(ForcesPlugin)
            .add(IntegratorPlugin)
            .add(MetricsPlugin)
            .add(ConstraintsPlugin)
            .add(CollisionPlugin)
            .add(ContactLoopPlugin)
            .add(transforms::TransformSyncPlugin)
            .add(anchors::AnchorPlugin)
            .add(colliders::ColliderPlugin)
            .add(contact_events::ContactEventsPlugin)
            .add(winch::WinchPlugin)
            .add(tearing::TearingPlugin)
            .add(sleeping::SleepPlugin)
    }
}

/// The schedules, particles, strands, the topology and the packed state: what every
/// other plugin of the crate builds on.
#[derive(Clone, Debug)]
pub struct StrandsCorePlugin {
    /// The schedule that runs a tick; `None` to drive by hand.
    pub driver: Option<InternedScheduleLabel>,
    /// World units per metre ([`LengthUnit`]).
    pub length_unit: f64,
}

impl Plugin for StrandsCorePlugin {
    fn build(&self, app: &mut App) {
        // The length unit's defaults, unless the app inserted its own settings first.
        let unit = self.length_unit;
        app.insert_resource(LengthUnit(unit));
        if !app.world().contains_resource::<StrandsConfig>() {
            app.insert_resource(StrandsConfig::with_length_unit(unit));
        }
        if !app.world().contains_resource::<CollisionConfig>() {
            app.insert_resource(CollisionConfig::with_length_unit(unit));
        }
        app.register_type::<LengthUnit>()
            .init_resource::<ParticleState>()
            .init_resource::<Topology>()
            .init_resource::<TopologyDirty>()
            .init_resource::<SpawnOrder>()
            .init_resource::<InputProblems>()
            .init_resource::<SimulationClock>()
            .register_type::<StrandsConfig>()
            .register_type::<SimulationClock>()
            .register_type::<world::particle::Particle>()
            .register_type::<world::particle::Position>()
            .register_type::<world::particle::Velocity>()
            .register_type::<world::particle::Mass>()
            .register_type::<world::particle::Pinned>()
            .register_type::<world::particle::Kinematic>()
            .register_type::<world::particle::ExternalForce>()
            .register_type::<world::particle::Tether>()
            .register_type::<world::strand::Strand>()
            .register_type::<world::strand::StrandMaterial>()
            .register_type::<world::strand::StrandKind>()
            .add_plugins(SchedulePlugin {
                driver: self.driver,
            })
            .add_systems(
                StrandsTick,
                (
                    (detect_strand_edits, rebuild_topology.run_if(topology_dirty))
                        .chain()
                        .in_set(TickSet::Topology),
                    gather.in_set(TickSet::Gather),
                    write_back.in_set(TickSet::Writeback),
                ),
            );
        guard::add_guard(app);
    }
}

/// The README's Rust snippets, compiled and run as doc tests so they keep working.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeSnippets;
