//! The Constrain stage: inextensibility as a velocity filter (DESIGN §5).
//!
//! After forces and the predictor, before collisions, every island's velocities are
//! projected so that each constrained edge ends the step at its rest length. Islands
//! are found once per topology change ([`islands`]); the kind of an island picks its
//! solver. Kernels are pure functions on slices ([`tridiagonal`], [`cyclic`],
//! [`projection`]); the systems here are thin adapters.

pub mod cyclic;
pub mod graph;
pub mod islands;
pub mod projection;
pub mod relaxation;
pub mod sparse;
pub mod tridiagonal;

use std::fmt;
use std::str::FromStr;

use bevy::prelude::*;

use crate::config::StrandsConfig;
use crate::metrics::IterationStats;
use crate::metrics::{StrandMetrics, count_elements};
use crate::schedule::{StepSet, StrandsStep, StrandsTick, TickSet};
use crate::state::ParticleState;
use crate::topology::{InputProblems, Topology, rebuild_topology};
use islands::{IslandKind, IslandSet, find_islands};
use projection::{
    Bodies, Chain, ConstraintDirection, ContactRow, Graph, IslandScratch, IslandView,
    ProjectionSettings, project_island,
};
use relaxation::{Relaxation, RelaxationScratch, relax};

/// How edges keep their length.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SolverKind {
    /// No constraints: every edge is a stretch spring.
    Springs,
    /// Exact projection: Thomas on paths and Sherman–Morrison on loops (linear time),
    /// sparse LDLᵀ on trees and graphs.
    #[default]
    Tridiagonal,
    /// Baseline: Gauss–Seidel relaxation, one edge at a time (position-based dynamics;
    /// zero-compliance XPBD), `max_iterations` sweeps.
    GaussSeidel,
    /// Baseline: Jacobi relaxation with per-particle averaging, `max_iterations` sweeps.
    Jacobi,
}

impl SolverKind {
    /// Every solver, in the order `strands run --help` lists them.
    pub const ALL: [SolverKind; 4] = [
        SolverKind::Tridiagonal,
        SolverKind::GaussSeidel,
        SolverKind::Jacobi,
        SolverKind::Springs,
    ];

    /// The name used on the command line and in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Springs => "springs",
            SolverKind::Tridiagonal => "tridiagonal",
            SolverKind::GaussSeidel => "gauss-seidel",
            SolverKind::Jacobi => "jacobi",
        }
    }

    /// One line on what the solver does.
    pub fn description(self) -> &'static str {
        match self {
            SolverKind::Springs => "stretch springs only, no constraints",
            SolverKind::Tridiagonal => {
                "exact fast projection; Thomas solve on paths, Sherman-Morrison on loops, sparse LDLT on trees and graphs (default)"
            }
            SolverKind::GaussSeidel => {
                "baseline: Gauss-Seidel relaxation (PBD, zero-compliance XPBD), --iterations sweeps per step"
            }
            SolverKind::Jacobi => {
                "baseline: Jacobi relaxation with averaging, --iterations sweeps per step"
            }
        }
    }

    /// The method this solver uses on islands of `kind`, if it takes them.
    pub fn method(self, kind: IslandKind) -> Option<&'static str> {
        match (self, kind) {
            (SolverKind::Tridiagonal, IslandKind::Path) => Some("Thomas"),
            (SolverKind::Tridiagonal, IslandKind::Cycle) => Some("cyclic (Sherman-Morrison)"),
            (SolverKind::Tridiagonal, IslandKind::Tree | IslandKind::Graph) => {
                Some("sparse LDLT (minimum degree)")
            }
            (SolverKind::GaussSeidel, _) => Some("Gauss-Seidel relaxation"),
            (SolverKind::Jacobi, _) => Some("Jacobi relaxation"),
            (SolverKind::Springs, _) => None,
        }
    }

    /// The relaxation this baseline solver sweeps with, if it is one.
    pub fn relaxation(self) -> Option<Relaxation> {
        match self {
            SolverKind::GaussSeidel => Some(Relaxation::GaussSeidel),
            SolverKind::Jacobi => Some(Relaxation::Jacobi),
            SolverKind::Springs | SolverKind::Tridiagonal => None,
        }
    }

    /// Whether contacts are fed back into the constraint solve as inequality rows
    /// (DESIGN §7). The baselines leave contacts to the collision impulses alone, as the
    /// engines they stand for do.
    pub fn projects_contacts(self) -> bool {
        self == SolverKind::Tridiagonal
    }

    /// Whether the solver can solve islands of `kind`.
    pub fn solves(self, kind: IslandKind) -> bool {
        self.method(kind).is_some()
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
            contact_tolerance: 0.0,
            max_correction: f64::INFINITY,
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
    island_of_particle: Vec<u32>,
    touched: Vec<(u32, u32)>,
    rows: Vec<ContactRow>,
    scratch: IslandScratch,
    relaxation: RelaxationScratch,
}

impl Islands {
    /// Count of islands of `kind` (solved or not).
    pub fn count(&self, kind: IslandKind) -> usize {
        self.set.islands.iter().filter(|i| i.kind == kind).count()
    }

    /// The solved island a particle belongs to, if any.
    pub fn island_of(&self, particle: usize) -> Option<usize> {
        self.island_of_particle
            .get(particle)
            .copied()
            .filter(|&i| i != NO_ISLAND)
            .map(|i| i as usize)
    }

    fn view(&self, island: usize) -> IslandView<'_> {
        let island = &self.set.islands[island];
        let edges = &self.set.edges[island.edges.clone()];
        match island.graph {
            Some(g) => IslandView::Graph(Graph {
                edges,
                layout: &self.set.graphs[g],
            }),
            None => IslandView::Chain(Chain {
                edges,
                closed: island.kind == IslandKind::Cycle,
            }),
        }
    }

    /// Project every solved island (the Constrain stage), recording each solve.
    pub fn project(
        &mut self,
        bodies: &mut Bodies,
        dt: f64,
        settings: &ProjectionSettings,
        stats: &mut IterationStats,
    ) {
        for slot in 0..self.solved.len() {
            let i = self.solved[slot];
            self.project_island(i, bodies, &[], dt, settings, stats);
        }
    }

    /// Relax every solved island (the Constrain stage of the baseline solvers),
    /// recording each solve.
    pub fn relax(
        &mut self,
        method: Relaxation,
        bodies: &mut Bodies,
        dt: f64,
        settings: &ProjectionSettings,
        stats: &mut IterationStats,
    ) {
        for &i in &self.solved {
            let bodies = Bodies {
                position: bodies.position,
                velocity: &mut *bodies.velocity,
                inverse_mass: bodies.inverse_mass,
            };
            let edges = &self.set.edges[self.set.islands[i].edges.clone()];
            let outcome = relax(edges, bodies, dt, method, settings, &mut self.relaxation);
            stats.record(&outcome);
        }
    }

    /// Project again the islands that `contacts` touch, each with its contact rows
    /// (DESIGN §7): Gauss–Seidel sweeps over those islands, each solved exactly with
    /// the other sides of its contacts frozen, until no contact falls short by more than
    /// the settings' contact tolerance or [`CONTACT_SWEEPS`] are done. Returns the
    /// largest shortfall left, as a speed.
    pub fn project_with_contacts(
        &mut self,
        bodies: &mut Bodies,
        contacts: &[ContactRow],
        dt: f64,
        settings: &ProjectionSettings,
        stats: &mut IterationStats,
    ) -> f64 {
        let tolerance = settings.contact_tolerance / dt;
        // Which islands each contact touches, grouped by island.
        self.touched.clear();
        for (c, row) in contacts.iter().enumerate() {
            for &p in &row.particles {
                if let Some(i) = self.island_of(p as usize) {
                    self.touched.push((i as u32, c as u32));
                }
            }
        }
        self.touched.sort_unstable();
        self.touched.dedup();
        let crosses_islands = contacts.iter().any(|row| {
            let mut islands = row
                .particles
                .iter()
                .filter_map(|&p| self.island_of(p as usize));
            islands
                .next()
                .is_some_and(|first| islands.any(|i| i != first))
        });
        let mut shortfall = contacts
            .iter()
            .map(|row| row.target - row.normal_velocity(bodies.velocity))
            .fold(0.0, f64::max);
        for _ in 0..CONTACT_SWEEPS {
            let mut start = 0;
            while start < self.touched.len() {
                let island = self.touched[start].0;
                let end = start
                    + self.touched[start..]
                        .iter()
                        .take_while(|t| t.0 == island)
                        .count();
                self.rows.clear();
                for &(_, c) in &self.touched[start..end] {
                    self.rows.push(contacts[c as usize]);
                }
                let rows = std::mem::take(&mut self.rows);
                self.project_island(island as usize, bodies, &rows, dt, settings, stats);
                self.rows = rows;
                start = end;
            }
            shortfall = contacts
                .iter()
                .map(|row| row.target - row.normal_velocity(bodies.velocity))
                .fold(0.0, f64::max);
            // Each island met its own contacts exactly; only contacts between islands
            // can have been disturbed since.
            if !crosses_islands || shortfall <= tolerance {
                break;
            }
        }
        shortfall
    }

    fn project_island(
        &mut self,
        island: usize,
        bodies: &mut Bodies,
        contacts: &[ContactRow],
        dt: f64,
        settings: &ProjectionSettings,
        stats: &mut IterationStats,
    ) {
        let mut scratch = std::mem::take(&mut self.scratch);
        let bodies = Bodies {
            position: bodies.position,
            velocity: &mut *bodies.velocity,
            inverse_mass: bodies.inverse_mass,
        };
        let outcome = project_island(
            self.view(island),
            bodies,
            contacts,
            dt,
            settings,
            &mut scratch,
        );
        stats.record(&outcome);
        self.scratch = scratch;
    }
}

const NO_ISLAND: u32 = u32::MAX;

/// Gauss–Seidel sweeps over the islands in contact, at most, per re-projection.
pub const CONTACT_SWEEPS: u32 = 8;

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
    let (mut longest, mut most_particles) = (0, 0);
    for (i, island) in set.islands.iter().enumerate() {
        if config.solver == SolverKind::Springs {
            continue;
        }
        if config.solver.solves(island.kind) && !island.duplicate_edge {
            solved.push(i);
            let particles = island
                .graph
                .map_or(island.edges.len() + 1, |g| set.graphs[g].particles.len());
            longest = longest.max(island.edges.len());
            most_particles = most_particles.max(particles);
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
    islands.scratch.reserve(longest, most_particles);
    islands.relaxation.reserve(topology.pinned.len(), longest);
    islands.island_of_particle.clear();
    islands
        .island_of_particle
        .resize(topology.pinned.len(), NO_ISLAND);
    for &i in &solved {
        for e in &set.edges[set.islands[i].edges.clone()] {
            for p in [e.a as usize, e.b as usize] {
                if !topology.pinned[p] {
                    islands.island_of_particle[p] = i as u32;
                }
            }
        }
    }
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
    let ParticleState {
        position,
        velocity,
        inverse_mass,
        ..
    } = &mut *state;
    let mut bodies = Bodies {
        position,
        velocity,
        inverse_mass,
    };
    let settings = config.projection();
    match config.solver.relaxation() {
        Some(method) => islands.relax(
            method,
            &mut bodies,
            step.dt,
            &settings,
            &mut metrics.projection,
        ),
        None => islands.project(&mut bodies, step.dt, &settings, &mut metrics.projection),
    }
}
