//! Configuration resources: the step, the constraint solver, collisions and the contact
//! loop. Every tunable of the simulation lives here, with its default and its meaning;
//! [`validate`](StrandsConfig::validate) methods check each number against that meaning,
//! and scene files deserialize into these same types (feature `serde`).

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::collision::broad_phase::BroadPhaseMethod;
use crate::constraints::projection::{ConstraintDirection, MAX_RESTEP_DEPTH, ProjectionSettings};
use crate::constraints::solver::SolverKind;
use crate::contact::settings::ContactSolver;
use crate::model::validate::{
    NumberError, at_least, finite_vector, non_negative, positive, within,
};
use crate::world::strand::StrandMaterial;

/// Step size, substeps and the global force parameters.
///
/// Each fixed tick runs `substeps` steps of `dt` seconds. The defaults are the
/// canonical scenes': 6 steps of 1/600 s per 1/100 s tick, the largest step at which
/// the factories stay exact and uncrossed at a fraction of the cost of 1/3000 (see
/// docs/step-size.md).
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
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
#[reflect(Resource)]
pub struct StrandsConfig {
    /// Step size in seconds. Driven by a schedule, the plugin sets it to the
    /// schedule's delta divided by `substeps`; driven by hand, it is the step.
    pub dt: f64,
    /// Steps per tick.
    pub substeps: u32,
    /// Gravity acceleration.
    pub gravity: DVec2,
    /// Mass-proportional damping coefficient (1/s): `f = −c m v`.
    pub damping: f64,
    /// Material of strands that carry no [`StrandMaterial`] of their own.
    pub material: StrandMaterial,
    /// The bending model: the turning-angle model (explicit) or the isometric
    /// quadratic one (implicit).
    pub bending: BendingModel,
    /// Whether ticks advance the simulation. A paused simulation keeps its state.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub paused: bool,
    /// Threads a stage may use (0: one per core). Results are the same bit for bit
    /// whatever the count; on the web there is one.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub threads: usize,
    /// The most particles the world simulates: strands (and loose particles) past it
    /// are left out at the topology rebuild, with a message in `InputProblems`.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub max_particles: usize,
    /// The most edges the world simulates, likewise.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub max_edges: usize,
    /// A step that would end in the collision fail-safe (impact zones moved rigidly) is
    /// put back and taken as two steps of half its size, each halved again if it too
    /// would, down to `dt / 2^max_step_halvings`; 0: never.
    pub max_step_halvings: u32,
    /// A step that follows a hard one (the contact solve left approaches to the
    /// collision impulses or ran out of Newton steps, or the step was halved) is taken
    /// in parts from the start, down to `dt / 2^max_split_ahead` (and no finer than
    /// `max_step_halvings` allows); eight easy steps in a row grow the parts back one
    /// level. 0: never. Cheaper than halving at a game's step, where a landing makes
    /// step after step hard (docs/step-size.md).
    pub max_split_ahead: u32,
    /// When strands at rest go to sleep, and whether they do.
    pub sleep: SleepConfig,
}

/// Sleeping: a strand whose every particle has stayed within `drift` of one place for
/// `time` seconds, as have the awake strands it touches, goes to sleep — held exactly
/// where it is, at no cost to a step but being collided against — and wakes when
/// something moving comes within reach of it, when one of its particles is written to,
/// when one of its anchors moves, or when what it rests on is despawned (see the
/// `sleeping` module).
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct SleepConfig {
    /// Whether strands sleep.
    pub enabled: bool,
    /// A unit rests while every particle of it stays within `drift` (world units) of
    /// where its rest began: a bound on where it goes, not on its speed at one
    /// instant, since strands held in a pile tremble by centimetres a second about
    /// places they do not leave. 2 cm by default.
    pub drift: f64,
    /// Seconds a strand must rest before it sleeps: a swing longer than `drift` within
    /// this time keeps a pendulum awake. 1 s by default.
    pub time: f64,
    /// The speed (world units per second) of something moving: a particle faster than
    /// this, of a unit whose mean speed since its rest began is faster too (or of a
    /// wall), wakes what it will come near. 5 cm/s by default, Box2D's threshold.
    pub speed: f64,
    /// A rigid body that strands touch or hold is let sleep (by its engine, with the
    /// strands under it) only once its points move slower than this (world units per
    /// second) and those strands have rested `time`: an engine's own threshold (avian's
    /// 15 cm/s) would freeze a crate still rocking on a rope. 1 mm/s by default.
    pub body_speed: f64,
}

impl Default for SleepConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            drift: 0.02,
            time: 1.0,
            speed: 0.05,
            body_speed: 1e-3,
        }
    }
}

impl SleepConfig {
    /// No sleeping.
    pub fn never() -> Self {
        Self {
            enabled: false,
            ..Self::default()
        }
    }

    /// Check every number against its meaning.
    pub fn validate(&self) -> Result<(), NumberError> {
        non_negative("drift", self.drift)?;
        non_negative("speed", self.speed)?;
        non_negative("body_speed", self.body_speed)?;
        non_negative("time", self.time)
    }
}

/// How bending forces are computed.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(into = "String", try_from = "String")
)]
pub enum BendingModel {
    /// `K (θ − θ̄)²` in the turning angle, its force and damping taken at the end of
    /// the step (linearly implicit: [`crate::forces::implicit_angle`]), so stiff
    /// bending on short edges stays stable at a game's step.
    #[default]
    Angle,
    /// The same energy integrated explicitly ([`crate::forces::bending`]): stable only
    /// while the step is short of the stiffest bend's period over π — for studies.
    AngleExplicit,
    /// `K |d|²` in the bend vector, a quadratic form with a constant Hessian on
    /// exact-length edges, integrated implicitly
    /// ([`crate::forces::quadratic_bending`], [`crate::forces::implicit_bending`]).
    Quadratic,
}

impl BendingModel {
    /// Every model.
    pub const ALL: [BendingModel; 3] = [
        BendingModel::Angle,
        BendingModel::AngleExplicit,
        BendingModel::Quadratic,
    ];

    /// The name used on the command line and in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            BendingModel::Angle => "angle",
            BendingModel::AngleExplicit => "angle-explicit",
            BendingModel::Quadratic => "quadratic",
        }
    }
}

impl std::fmt::Display for BendingModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for BendingModel {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown bending model '{s}'; valid models: angle, angle-explicit, quadratic"
                )
            })
    }
}

impl From<BendingModel> for String {
    fn from(model: BendingModel) -> String {
        model.name().to_string()
    }
}

impl TryFrom<String> for BendingModel {
    type Error = String;

    fn try_from(name: String) -> Result<Self, Self::Error> {
        name.parse()
    }
}

/// World units per metre (like avian's `PhysicsLengthUnit`): 1 for a world in metres,
/// 100 for one in pixels at 100 pixels a metre. It scales the defaults that carry a
/// length — gravity, the collision thickness, the default material's stiffness — so a
/// scaled world behaves as the metre world does, scaled; every other tolerance of the
/// crate is relative already (to the thickness or to rest lengths). Set it through
/// `StrandsPlugin::with_length_unit`; it does not rescale configurations you insert.
#[derive(Resource, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Resource)]
pub struct LengthUnit(pub f64);

impl Default for LengthUnit {
    fn default() -> Self {
        LengthUnit(1.0)
    }
}

/// [`StrandsConfig::max_particles`] by default: 4 million (about 1 GiB of state and
/// solver buffers).
pub const DEFAULT_MAX_PARTICLES: usize = 4_000_000;

impl Default for StrandsConfig {
    fn default() -> Self {
        Self {
            dt: 1.0 / 600.0,
            substeps: 6,
            gravity: DVec2::new(0.0, -9.81),
            damping: 0.0,
            material: StrandMaterial::default(),
            bending: BendingModel::default(),
            paused: false,
            threads: 0,
            max_particles: DEFAULT_MAX_PARTICLES,
            max_edges: 2 * DEFAULT_MAX_PARTICLES,
            max_step_halvings: 6,
            max_split_ahead: DEFAULT_SPLIT_AHEAD,
            sleep: SleepConfig::default(),
        }
    }
}

impl StrandsConfig {
    /// The defaults for a world of `unit` world units per metre: gravity and the
    /// default material scaled with it.
    pub fn with_length_unit(unit: f64) -> Self {
        let default = Self::default();
        Self {
            gravity: default.gravity * unit,
            material: default.material.with_length_unit(unit),
            sleep: SleepConfig {
                drift: default.sleep.drift * unit,
                speed: default.sleep.speed * unit,
                body_speed: default.sleep.body_speed * unit,
                ..default.sleep
            },
            ..default
        }
    }

    /// Simulated seconds per fixed tick.
    pub fn tick_seconds(&self) -> f64 {
        self.dt * self.substeps as f64
    }

    /// The threads a stage uses: [`StrandsConfig::threads`], with 0 meaning one per
    /// core, and one where threads cannot be spawned (wasm32).
    pub fn worker_threads(&self) -> usize {
        if cfg!(target_arch = "wasm32") {
            return 1;
        }
        // Asking the system reads files (and allocates): once per process.
        static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
        match self.threads {
            0 => *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
            n => n,
        }
    }

    /// Check every number against its meaning.
    pub fn validate(&self) -> Result<(), NumberError> {
        positive("dt", self.dt)?;
        at_least("substeps", self.substeps as usize, 1, "a tick")?;
        finite_vector("gravity", self.gravity)?;
        non_negative("damping", self.damping)?;
        halvings("max_step_halvings", self.max_step_halvings)?;
        halvings("max_split_ahead", self.max_split_ahead)?;
        self.sleep.validate().map_err(|e| e.within("sleep"))?;
        self.material.validate().map_err(|e| e.within("material"))
    }
}

/// A count of halvings of the step, at most [`MAX_STEP_HALVINGS`].
fn halvings(field: &str, value: u32) -> Result<(), NumberError> {
    if value > MAX_STEP_HALVINGS {
        return Err(NumberError {
            field: field.into(),
            problem: format!(
                "must be at most {MAX_STEP_HALVINGS} (steps of dt / 2^{MAX_STEP_HALVINGS}), got {value}"
            ),
        });
    }
    Ok(())
}

/// [`StrandsConfig::max_split_ahead`]'s default: a hard step's successors in quarters.
pub const DEFAULT_SPLIT_AHEAD: u32 = 2;

/// The most halvings [`StrandsConfig::max_step_halvings`] may ask for.
pub const MAX_STEP_HALVINGS: u32 = 16;

/// Constraint solver settings.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_strands::prelude::*;
/// # use bevy_strands::constraints::projection::ConstraintDirection;
/// let mut app = App::new();
/// app.add_plugins(StrandsPlugin::manual());
/// let mut config = app.world_mut().resource_mut::<ConstraintConfig>();
/// config.tolerance = 1e-10;
/// config.direction = ConstraintDirection::StartOfStep;
/// ```
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
#[reflect(Resource)]
pub struct ConstraintConfig {
    /// The solver.
    pub solver: SolverKind,
    /// Stop projecting when every `|C_k| / L_k²` is at most this (≈ twice the
    /// relative length error).
    pub tolerance: f64,
    /// Linear solves per island per step at most (sweeps, for the relaxation baselines).
    pub max_iterations: u32,
    /// Where the constraint direction is evaluated.
    pub direction: ConstraintDirection,
    /// Keep stretch springs on constrained edges too (constraint-drift studies).
    pub stretch_springs: bool,
    /// An island whose projection does not converge in `max_iterations` is stepped
    /// again in substeps, halved where they fail down to `dt / 2^max_restep_depth`
    /// (at most 30); 0 turns re-stepping off, leaving such a projection capped.
    pub max_restep_depth: u32,
}

impl Default for ConstraintConfig {
    fn default() -> Self {
        Self {
            solver: SolverKind::Tridiagonal,
            tolerance: 1e-12,
            max_iterations: 20,
            direction: ConstraintDirection::EndOfStep,
            stretch_springs: false,
            max_restep_depth: 12,
        }
    }
}

impl ConstraintConfig {
    /// The projection's stopping rule.
    pub fn projection(&self) -> ProjectionSettings {
        ProjectionSettings {
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
            direction: self.direction,
            max_restep_depth: self.max_restep_depth,
        }
    }

    /// Check every number against its meaning.
    pub fn validate(&self) -> Result<(), NumberError> {
        positive("tolerance", self.tolerance)?;
        at_least("max_iterations", self.max_iterations as usize, 1, "a solve")?;
        if self.max_restep_depth > MAX_RESTEP_DEPTH {
            return Err(NumberError {
                field: "max_restep_depth".into(),
                problem: format!(
                    "must be at most {MAX_RESTEP_DEPTH} (substeps of dt / 2^{MAX_RESTEP_DEPTH}), got {}",
                    self.max_restep_depth
                ),
            });
        }
        Ok(())
    }
}

/// Collision settings.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_strands::prelude::*;
/// let mut app = App::new();
/// app.add_plugins(StrandsPlugin::manual());
/// let mut config = app.world_mut().resource_mut::<CollisionConfig>();
/// config.friction = 0.5;
/// config.thickness = 0.002;
/// ```
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
#[reflect(Resource)]
pub struct CollisionConfig {
    /// Whether the Collide stage runs.
    pub enabled: bool,
    /// Thickness `h`: pairs are kept at least this far apart.
    pub thickness: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Restitution of collision impulses (0: inelastic, 1: elastic).
    pub restitution: f64,
    /// Detection passes before the fail-safe.
    pub max_iterations: u32,
    /// The gap a collision leaves between a point and an edge, as a fraction of the
    /// thickness. The default, a millionth, is far above rounding (a point resting
    /// within rounding of an edge's line has no reliable side) and far below anything
    /// visible or any motion the cushion makes.
    pub separation: f64,
    /// How candidate pairs are found.
    pub broad_phase: BroadPhaseMethod,
    /// Count edge crossings at the end of every step.
    pub check_crossings: bool,
}

impl Default for CollisionConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            thickness: 0.004,
            friction: 0.3,
            restitution: 0.0,
            max_iterations: 10,
            separation: 1e-6,
            broad_phase: BroadPhaseMethod::Grid,
            check_crossings: false,
        }
    }
}

impl CollisionConfig {
    /// The defaults for a world of `unit` world units per metre: the thickness scaled.
    pub fn with_length_unit(unit: f64) -> Self {
        let default = Self::default();
        Self {
            thickness: default.thickness * unit,
            ..default
        }
    }

    /// Check every number against its meaning.
    pub fn validate(&self) -> Result<(), NumberError> {
        positive("thickness", self.thickness)?;
        non_negative("friction", self.friction)?;
        within("restitution", self.restitution, 0.0..=1.0)?;
        within("separation", self.separation, 0.0..=1.0)?;
        at_least(
            "max_iterations",
            self.max_iterations as usize,
            1,
            "detection",
        )
    }
}

/// The contact loop's settings: how constraint re-projections with contact rows
/// alternate with collision impulses inside the Collide stage.
///
/// After the first round of impulses, the islands that contacts touched are projected
/// onto their constraints again with every contact as an inequality row, then detection
/// runs again; this repeats until a pass applies no impulse or `passes` are done.
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
#[reflect(Resource)]
pub struct ContactConfig {
    /// Alternations of re-projection and collisions at most; they stop as soon as a
    /// pass finds no new collision, so at small steps one or two run whatever the cap.
    /// 0 leaves edges next to contacts as the impulses leave them.
    pub passes: u32,
    /// Gauss–Seidel sweeps over the contact rows per Newton step of a contact
    /// projection, at most. The impulses are warm-started from the previous step, so
    /// a resting pile needs few; the cap bounds a step's cost when many contacts
    /// change at once.
    pub sweeps: u32,
    /// A contact projection that would move any particle by more than this many of its
    /// island's shortest rest lengths in one step is refused for that island: room for
    /// a strand that lands moving a good part of an edge per step, while a nearly
    /// dependent set of rows asking for absurd corrections is still refused.
    pub max_correction: f64,
    /// Contact rows are met to this many thicknesses per second (a row may end the
    /// step short of its target by `tolerance × thickness × dt`, and by no more than
    /// at a step of 1/300 s at longer steps); the edges are met exactly whatever the
    /// contacts do. It is the speed at which a resting pile may creep into its
    /// cushion between steps.
    pub tolerance: f64,
    /// A contact group at rest — its free particles' mean speed, apart from the step's
    /// fall under gravity, below the sleeping speed (`SleepConfig::speed`) — has its
    /// rows met to this many thicknesses per second instead, with up to
    /// `rest_sweeps` sweeps: at `tolerance` the sweeps leave a pile held by friction
    /// trembling a few centimetres per second for as long as it runs.
    pub rest_tolerance: f64,
    /// Gauss–Seidel sweeps per Newton step of a group at rest, at most.
    pub rest_sweeps: u32,
    /// A pair inside the cushion may stay where it is while it is at least this
    /// fraction of the thickness apart; closer, its row pushes it out to it. Asking
    /// every resting pair back to the full thickness makes a pile breathe.
    pub keep: f64,
    /// Pairs that start or would end the step within this many thicknesses get a
    /// row.
    pub reach: f64,
    /// Run the contact solve before any impulse (speculative contacts): every pair
    /// within reach becomes a row of a contact projection, so landings, resting contact
    /// and strands lying on strands are met inside the exact projection, both sides
    /// moving, rather than by impulses. Off, proximity and collision impulses do the
    /// work and the contact loop re-projects what they stretched.
    pub speculative: bool,
    /// How a contact projection finds its rows' impulses: by default (`Auto`) each
    /// group by whichever costs it less, Newton's method on the rows and edges
    /// together for long strands or projected Gauss–Seidel over each row's response on
    /// its whole strands for short ones; either can be asked for.
    pub solver: ContactSolver,
}

impl Default for ContactConfig {
    fn default() -> Self {
        Self {
            passes: 16,
            sweeps: 16,
            max_correction: 2.0,
            tolerance: 1.0,
            rest_tolerance: 0.01,
            rest_sweeps: 64,
            keep: 0.5,
            reach: 2.0,
            speculative: true,
            solver: ContactSolver::Auto,
        }
    }
}

impl ContactConfig {
    /// Check every number against its meaning.
    pub fn validate(&self) -> Result<(), NumberError> {
        at_least("sweeps", self.sweeps as usize, 1, "a re-projection")?;
        positive("max_correction", self.max_correction)?;
        positive("tolerance", self.tolerance)?;
        positive("rest_tolerance", self.rest_tolerance)?;
        at_least(
            "rest_sweeps",
            self.rest_sweeps as usize,
            1,
            "a re-projection at rest",
        )?;
        within("keep", self.keep, 0.0..=1.0)?;
        non_negative("reach", self.reach)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halvings_and_splits_past_the_finest_step_are_refused_by_name() {
        assert!(StrandsConfig::default().validate().is_ok());
        for (field, set) in [
            (
                "max_step_halvings",
                (|c: &mut StrandsConfig| c.max_step_halvings = 17) as fn(&mut StrandsConfig),
            ),
            ("max_split_ahead", |c: &mut StrandsConfig| {
                c.max_split_ahead = 17
            }),
        ] {
            let mut config = StrandsConfig::default();
            set(&mut config);
            let error = config.validate().unwrap_err();
            assert_eq!(error.field, field);
            assert!(error.problem.contains("got 17"), "{}", error.problem);
        }
        let finest = StrandsConfig {
            max_split_ahead: MAX_STEP_HALVINGS,
            ..Default::default()
        };
        assert!(finest.validate().is_ok());
    }
}
