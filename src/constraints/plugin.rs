//! The Constrain stage's systems and the islands they solve: found once per topology
//! change, each projected every step by the kernel its kind calls for.

use bevy::prelude::*;

use super::islands::{IslandKind, IslandSet, find_islands};
use super::projection::{
    Bodies, Chain, ContactRow, Graph, IslandScratch, IslandView, ProjectionSettings, project_island,
};
use super::relaxation::{Relaxation, RelaxationScratch, relax};
use super::solver::SolverKind;
use crate::metrics::{IterationStats, StrandMetrics, count_elements};
use crate::model::NO_ISLAND;
use crate::schedule::{ConstrainSet, StrandsStep, StrandsTick, TickSet};
use crate::world::config::{ConstraintConfig, StrandsConfig};
use crate::world::problems::InputProblems;
use crate::world::state::ParticleState;
use crate::world::topology::{Topology, rebuild_topology};

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

    /// Project island `island` alone, with no contact rows; whether it met its edges.
    pub fn project_alone(
        &mut self,
        island: usize,
        bodies: &mut Bodies,
        dt: f64,
        settings: &ProjectionSettings,
        stats: &mut IterationStats,
    ) -> bool {
        self.project_island(island, bodies, &[], dt, settings, stats)
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
            let edges = &self.set.edges[self.set.islands[i].edges.clone()];
            let outcome = relax(
                edges,
                bodies.reborrow(),
                dt,
                method,
                settings,
                &mut self.relaxation,
            );
            stats.record(&outcome);
        }
    }

    /// Project again the islands that `contacts` touch (`island` gives each particle's,
    /// as [`Topology::island`] does), each with its contact rows:
    /// Gauss–Seidel sweeps over those islands, each solved exactly with the other sides
    /// of its contacts frozen, until no contact falls short by more than the settings'
    /// contact tolerance or `sweeps` are done. Each island's last projection is told in
    /// `outcomes` (island, whether it met its edges). Returns the largest shortfall
    /// left, as a speed.
    #[allow(clippy::too_many_arguments)]
    pub fn project_with_contacts(
        &mut self,
        island: &[u32],
        bodies: &mut Bodies,
        contacts: &[ContactRow],
        dt: f64,
        settings: &ProjectionSettings,
        sweeps: u32,
        stats: &mut IterationStats,
        outcomes: &mut Vec<(u32, bool)>,
    ) -> f64 {
        outcomes.clear();
        let tolerance = settings.contact_tolerance / dt;
        // Which islands each contact touches, grouped by island.
        self.touched.clear();
        for (c, row) in contacts.iter().enumerate() {
            for &p in &row.particles {
                if let Some(i) = island_of(island, p as usize) {
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
                .filter_map(|&p| island_of(island, p as usize));
            islands
                .next()
                .is_some_and(|first| islands.any(|i| i != first))
        });
        let mut shortfall = contacts
            .iter()
            .map(|row| row.target - row.normal_velocity(bodies.velocity))
            .fold(0.0, f64::max);
        for _ in 0..sweeps {
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
                let met = self.project_island(island as usize, bodies, &rows, dt, settings, stats);
                match outcomes.iter_mut().find(|(i, _)| *i == island) {
                    Some(outcome) => outcome.1 = met,
                    None => outcomes.push((island, met)),
                }
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
    ) -> bool {
        let mut scratch = std::mem::take(&mut self.scratch);
        let outcome = project_island(
            self.view(island),
            bodies.reborrow(),
            contacts,
            dt,
            settings,
            &mut scratch,
        );
        stats.record(&outcome);
        self.scratch = scratch;
        outcome.converged && !outcome.rejected && !outcome.singular
    }
}

/// The island of `particle`, if it is in one.
fn island_of(island: &[u32], particle: usize) -> Option<usize> {
    island
        .get(particle)
        .copied()
        .filter(|&i| i != NO_ISLAND)
        .map(|i| i as usize)
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
            .add_systems(StrandsStep, solve_constraints.in_set(ConstrainSet::Project));
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
    topology.island.clear();
    topology.island.resize(topology.pinned.len(), NO_ISLAND);
    for &i in &solved {
        for e in &set.edges[set.islands[i].edges.clone()] {
            for p in [e.a as usize, e.b as usize] {
                if !topology.pinned[p] {
                    topology.island[p] = i as u32;
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
    let mut bodies = Bodies::new(position, velocity, inverse_mass);
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
