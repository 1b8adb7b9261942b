//! The Constrain stage: inextensibility as a velocity filter (DESIGN §5).
//!
//! After forces and the predictor, before collisions, every island's velocities are
//! projected so that each constrained edge ends the step at its rest length. Islands
//! are found once per topology change ([`islands`]); the kind of an island picks its
//! solver. Kernels are pure functions on slices ([`tridiagonal`], [`cyclic`],
//! [`projection`]); the systems here are thin adapters.

pub mod cyclic;
pub mod islands;
pub mod projection;
pub mod tridiagonal;

use std::fmt;
use std::str::FromStr;

use bevy::prelude::*;

use crate::config::StrandsConfig;
use crate::metrics::{StrandMetrics, count_elements};
use crate::schedule::{StepSet, StrandsStep, StrandsTick, TickSet};
use crate::state::ParticleState;
use crate::topology::{InputProblems, Topology, rebuild_topology};
use islands::{IslandKind, IslandSet, find_islands};
use projection::{Chain, ChainScratch, ConstraintDirection, ProjectionSettings, project_chain};

/// How edges keep their length.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SolverKind {
    /// No constraints: every edge is a stretch spring.
    Springs,
    /// Exact projection, linear time: Thomas on paths, Sherman–Morrison on loops.
    #[default]
    Tridiagonal,
}

impl SolverKind {
    /// Every solver, in the order `strands run --help` lists them.
    pub const ALL: [SolverKind; 2] = [SolverKind::Tridiagonal, SolverKind::Springs];

    /// The name used on the command line and in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Springs => "springs",
            SolverKind::Tridiagonal => "tridiagonal",
        }
    }

    /// One line on what the solver does.
    pub fn description(self) -> &'static str {
        match self {
            SolverKind::Springs => "stretch springs only, no constraints",
            SolverKind::Tridiagonal => {
                "exact fast projection; Thomas solve on paths, Sherman-Morrison on loops (default)"
            }
        }
    }

    /// Whether the solver can solve islands of `kind`.
    pub fn solves(self, kind: IslandKind) -> bool {
        match self {
            SolverKind::Springs => false,
            SolverKind::Tridiagonal => matches!(kind, IslandKind::Path | IslandKind::Cycle),
        }
    }
}

impl fmt::Display for SolverKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SolverKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|k| k.name()).collect();
                format!("unknown solver '{s}'; valid solvers: {}", names.join(", "))
            })
    }
}

/// Constraint solver settings.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_strands::prelude::*;
/// # use bevy_strands::constraints::{ConstraintConfig, projection::ConstraintDirection};
/// let mut app = App::new();
/// app.add_plugins(StrandsPlugin::manual());
/// let mut config = app.world_mut().resource_mut::<ConstraintConfig>();
/// config.tolerance = 1e-10;
/// config.direction = ConstraintDirection::StartOfStep;
/// ```
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[reflect(Resource)]
pub struct ConstraintConfig {
    /// The solver.
    pub solver: SolverKind,
    /// Stop projecting when every `|C_k| / L_k²` is at most this (≈ twice the
    /// relative length error).
    pub tolerance: f64,
    /// Linear solves per island per step at most.
    pub max_iterations: u32,
    /// Where the constraint direction is evaluated.
    pub direction: ConstraintDirection,
    /// Keep stretch springs on constrained edges too (constraint-drift studies).
    pub stretch_springs: bool,
}

impl Default for ConstraintConfig {
    fn default() -> Self {
        Self {
            solver: SolverKind::Tridiagonal,
            tolerance: 1e-12,
            max_iterations: 20,
            direction: ConstraintDirection::EndOfStep,
            stretch_springs: false,
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
        }
    }
}

/// The islands of the current topology and the solver's reusable buffers.
#[derive(Resource, Default, Debug)]
pub struct Islands {
    /// Topology version the islands were built from.
    pub version: u64,
    /// The islands.
    pub set: IslandSet,
    /// Indices of the islands the configured solver solves.
    pub solved: Vec<usize>,
    /// Islands of a kind the configured solver cannot solve (their edges keep stretch
    /// springs).
    pub unsolved: Vec<usize>,
    scratch: ChainScratch,
}

impl Islands {
    /// Count of islands of `kind` (solved or not).
    pub fn count(&self, kind: IslandKind) -> usize {
        self.set.islands.iter().filter(|i| i.kind == kind).count()
    }
}

/// Islands, the Constrain stage and its settings.
pub struct ConstraintsPlugin;

impl Plugin for ConstraintsPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ConstraintConfig>()
            .init_resource::<Islands>()
            .register_type::<ConstraintConfig>()
            .add_systems(
                StrandsTick,
                rebuild_islands
                    .in_set(TickSet::Topology)
                    .after(rebuild_topology)
                    .before(count_elements),
            )
            .add_systems(StrandsStep, solve_constraints.in_set(StepSet::Constrain));
    }
}

/// Re-find the islands after a topology change or a change of solver, and mark which
/// edges are constrained and which keep springs.
pub fn rebuild_islands(
    config: Res<ConstraintConfig>,
    mut topology: ResMut<Topology>,
    mut islands: ResMut<Islands>,
    mut problems: ResMut<InputProblems>,
) {
    if islands.version == topology.version && !config.is_changed() {
        return;
    }
    let set = find_islands(&topology.edges, &topology.pinned);
    let topology = &mut *topology;
    for edge in &mut topology.edges {
        edge.constrained = false;
        edge.spring = !edge.is_static && edge.stiffness > 0.0;
    }
    let (mut solved, mut unsolved) = (Vec::new(), Vec::new());
    let mut longest = 0;
    for (i, island) in set.islands.iter().enumerate() {
        if config.solver == SolverKind::Springs {
            continue;
        }
        if config.solver.solves(island.kind) && !island.duplicate_edge {
            solved.push(i);
            longest = longest.max(island.edges.len());
            for e in &set.edges[island.edges.clone()] {
                let edge = &mut topology.edges[e.edge as usize];
                edge.constrained = true;
                edge.spring = config.stretch_springs && edge.stiffness > 0.0;
            }
        } else {
            unsolved.push(i);
            let first = set.edges[island.edges.start].edge as usize;
            let strand = topology.strands[topology.edges[first].strand as usize].entity;
            let why = if island.duplicate_edge {
                "two of its edges join the same particles, a redundant constraint".to_string()
            } else {
                format!(
                    "the {} solver has no method for a {}",
                    config.solver,
                    island.kind.name()
                )
            };
            problems.report(
                strand,
                format!(
                    "a {} island of {} edges is not constrained: {why}; its edges keep stretch springs",
                    island.kind.name(),
                    island.edges.len()
                ),
            );
        }
    }
    islands.scratch.reserve(longest);
    islands.set = set;
    islands.solved = solved;
    islands.unsolved = unsolved;
    islands.version = topology.version;
}

/// The Constrain stage: project every solved island.
pub fn solve_constraints(
    config: Res<ConstraintConfig>,
    step: Res<StrandsConfig>,
    mut islands: ResMut<Islands>,
    mut state: ResMut<ParticleState>,
    mut metrics: ResMut<StrandMetrics>,
) {
    let settings = config.projection();
    let Islands {
        set,
        solved,
        scratch,
        ..
    } = &mut *islands;
    let ParticleState {
        position,
        velocity,
        inverse_mass,
        ..
    } = &mut *state;
    for &i in solved.iter() {
        let island = &set.islands[i];
        let chain = Chain {
            edges: &set.edges[island.edges.clone()],
            closed: island.kind == IslandKind::Cycle,
        };
        let outcome = project_chain(
            chain,
            position,
            velocity,
            inverse_mass,
            step.dt,
            &settings,
            scratch,
        );
        metrics
            .projection
            .record(outcome.iterations, outcome.converged);
    }
}
