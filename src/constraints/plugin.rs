//! The Constrain stage's systems and the islands they solve: found once per topology
//! change, each projected every step by the kernel its kind calls for.

use bevy::math::DVec2;
use bevy::prelude::*;

use super::islands::{IslandKind, IslandSet, find_islands};
use super::projection::{
    Bodies, Chain, Graph, IslandScratch, IslandView, ProjectionSettings, project_island,
};
use super::relaxation::{Relaxation, RelaxationScratch, relax};
use super::solver::SolverKind;
use crate::metrics::{IterationStats, StrandMetrics, count_elements};
use crate::model::NO_ISLAND;
use crate::parallel::alongside;
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
    scratch: IslandScratch,
    relaxation: RelaxationScratch,
    lanes: Vec<Lane>,
    /// Each topology edge's impulse this step, summed over every projection of the
    /// step (mass × length, tension positive): see [`Islands::edge_tension`].
    impulse: Vec<f64>,
}

/// Below this many edges in all the Constrain stage stays on one thread: starting
/// threads would cost more than the solves they share.
const PARALLEL_EDGES: usize = 4096;

/// One extra thread's share of a parallel Constrain stage: a copy of the velocities to
/// write its islands' into, its buffers, and its counts.
#[derive(Debug, Default)]
struct Lane {
    velocity: Vec<DVec2>,
    end_change: Vec<DVec2>,
    impulse: Vec<f64>,
    scratch: IslandScratch,
    stats: IterationStats,
    /// Its slots of `Islands::solved`.
    slots: std::ops::Range<usize>,
}

impl Islands {
    /// Count of islands of `kind` (solved or not).
    pub fn count(&self, kind: IslandKind) -> usize {
        self.set.islands.iter().filter(|i| i.kind == kind).count()
    }

    /// Project every solved island (the Constrain stage), recording each solve.
    ///
    /// With `threads` above one and enough edges, contiguous shares of the islands
    /// (about equal in edges) are projected on that many threads. An island's solve
    /// reads and writes its own particles only, the same whichever thread does it, so
    /// the velocities and counts are the same bit for bit whatever the thread count.
    pub fn project(
        &mut self,
        bodies: &mut Bodies,
        dt: f64,
        settings: &ProjectionSettings,
        stats: &mut IterationStats,
        threads: usize,
    ) {
        let edges: usize = (self.solved.iter())
            .map(|&i| self.set.islands[i].edges.len())
            .sum();
        let threads = threads.min(self.solved.len());
        if threads <= 1 || edges < PARALLEL_EDGES {
            for slot in 0..self.solved.len() {
                let i = self.solved[slot];
                self.project_alone(i, bodies, dt, settings, stats);
            }
            return;
        }
        let Islands {
            set,
            solved,
            scratch,
            lanes,
            impulse,
            ..
        } = self;
        lanes.resize_with(threads - 1, Lane::default);
        // Share boundaries: slot where the running edge count passes t/threads of all.
        let mut first = 0..solved.len();
        let (mut slot, mut count) = (0, 0);
        for t in 0..threads {
            let start = slot;
            let goal = edges * (t + 1) / threads;
            while slot < solved.len() && (count < goal || t + 1 == threads) {
                count += set.islands[solved[slot]].edges.len();
                slot += 1;
            }
            match t {
                0 => first = start..slot,
                _ => lanes[t - 1].slots = start..slot,
            }
        }
        let (position, inverse_mass) = (bodies.position, bodies.inverse_mass);
        for lane in lanes.iter_mut() {
            lane.velocity.clear();
            lane.velocity.extend_from_slice(bodies.velocity);
            lane.end_change.clear();
            lane.end_change.resize(bodies.velocity.len(), DVec2::ZERO);
            lane.impulse.clear();
            lane.impulse.resize(impulse.len(), 0.0);
            lane.stats = IterationStats::default();
        }
        let (set, solved) = (&*set, &*solved);
        alongside(
            lanes,
            |lane| {
                let mut own = Bodies::new(position, &mut lane.velocity, inverse_mass)
                    .with_end_change(&mut lane.end_change);
                for slot in lane.slots.clone() {
                    let view = IslandView::of(set, solved[slot]);
                    project_met(
                        view,
                        &mut own,
                        dt,
                        settings,
                        &mut lane.scratch,
                        &mut lane.stats,
                        &mut lane.impulse,
                    );
                }
            },
            || {
                for slot in first {
                    let view = IslandView::of(set, solved[slot]);
                    project_met(view, bodies, dt, settings, scratch, stats, impulse);
                }
            },
        );
        // Each lane's islands' velocities back; a pinned particle two islands share is
        // never written, so its copy is the value it had.
        for lane in lanes.iter() {
            for slot in lane.slots.clone() {
                for e in &set.edges[set.islands[solved[slot]].edges.clone()] {
                    for j in [e.a as usize, e.b as usize] {
                        bodies.velocity[j] = lane.velocity[j];
                        if let Some(end_change) = bodies.end_change.as_deref_mut() {
                            end_change[j] = lane.end_change[j];
                        }
                    }
                    impulse[e.edge as usize] += lane.impulse[e.edge as usize];
                }
            }
            stats.merge(&lane.stats);
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

    /// Project island `island` alone, with no contact rows; whether it met its edges.
    pub fn project_alone(
        &mut self,
        island: usize,
        bodies: &mut Bodies,
        dt: f64,
        settings: &ProjectionSettings,
        stats: &mut IterationStats,
    ) -> bool {
        let Islands {
            set,
            scratch,
            impulse,
            ..
        } = self;
        let view = IslandView::of(set, island);
        project_met(view, bodies, dt, settings, scratch, stats, impulse)
    }

    /// What the contact solve needs of the islands: the islands, and each topology
    /// edge's impulse this step to add its projections' to.
    pub(crate) fn contact_parts(&mut self) -> (&IslandSet, &mut [f64]) {
        (&self.set, &mut self.impulse)
    }

    /// Forget the last step's impulses (sized to the topology at its rebuild).
    pub fn begin_step(&mut self) {
        self.impulse.fill(0.0);
    }

    /// The tension of topology edge `edge` in the last step of `dt` (force; positive
    /// when the edge pulls its particles together, negative when it pushes them
    /// apart): the impulses of every projection of the step over dt². Zero for an edge
    /// no projection solved (a spring, a rigid zone's, a static one).
    pub fn edge_tension(&self, edge: usize, dt: f64) -> f64 {
        self.impulse.get(edge).map_or(0.0, |j| j / (dt * dt))
    }
}

/// Project `view`, record the solve and its edges' impulses (into `impulse`, by
/// topology edge), and tell whether it met its edges.
#[allow(clippy::too_many_arguments)]
fn project_met(
    view: IslandView,
    bodies: &mut Bodies,
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
    stats: &mut IterationStats,
    impulse: &mut [f64],
) -> bool {
    let edges = match view {
        IslandView::Chain(Chain { edges, .. }) | IslandView::Graph(Graph { edges, .. }) => edges,
    };
    let outcome = project_island(view, bodies.reborrow(), dt, settings, scratch);
    for (e, j) in edges.iter().zip(scratch.edge_impulses(edges.len())) {
        if let Some(slot) = impulse.get_mut(e.edge as usize) {
            *slot += j;
        }
    }
    stats.record(&outcome);
    outcome.converged && !outcome.rejected && !outcome.singular
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
    islands.impulse.clear();
    islands.impulse.resize(topology.edges.len(), 0.0);
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
        end_velocity_change,
        ..
    } = &mut *state;
    let mut bodies =
        Bodies::new(position, velocity, inverse_mass).with_end_change(end_velocity_change);
    let settings = config.projection();
    islands.begin_step();
    match config.solver.relaxation() {
        Some(method) => islands.relax(
            method,
            &mut bodies,
            step.dt,
            &settings,
            &mut metrics.projection,
        ),
        None => islands.project(
            &mut bodies,
            step.dt,
            &settings,
            &mut metrics.projection,
            step.worker_threads(),
        ),
    }
}
