//! The Constrain stage's systems and the islands they solve: found once per topology
//! change, each projected every step by the kernel its kind calls for.

use bevy::math::DVec2;
use bevy::prelude::*;

use super::island_edge::IslandEdge;
use super::islands::{IslandKind, IslandSet, find_islands};
use super::projection::{
    Bodies, Chain, ContactRow, Graph, IslandScratch, IslandView, ProjectionSettings, project_island,
};
use super::relaxation::{Relaxation, RelaxationScratch, relax};
use super::solver::SolverKind;
use crate::metrics::{IterationStats, StrandMetrics, count_elements};
use crate::model::NO_ISLAND;
use crate::model::union_find::UnionFind;
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
    units: UnionFind,
    /// (unit, island) of every island a contact touches, by unit.
    members: Vec<(u32, u32)>,
    row_ids: Vec<u32>,
    unit_rows: Vec<u32>,
    group_edges: Vec<IslandEdge>,
    rows: Vec<ContactRow>,
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

    /// Whether contact rows among particles of `islands` (each particle's island, or
    /// `NO_ISLAND` for a pinned one) can be projected as one unit: they touch at most
    /// one free island, or only paths.
    pub fn one_unit(&self, islands: [u32; 3]) -> bool {
        let mut free = islands.into_iter().filter(|&i| i != NO_ISLAND);
        let Some(first) = free.next() else {
            return true;
        };
        let is_path = |i: u32| self.set.islands[i as usize].kind == IslandKind::Path;
        let mut rest = free.filter(|&i| i != first).peekable();
        rest.peek().is_none() || (is_path(first) && rest.all(is_path))
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
                self.project_island(i, bodies, &[], dt, settings, stats);
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
            lane.impulse.clear();
            lane.impulse.resize(impulse.len(), 0.0);
            lane.stats = IterationStats::default();
        }
        let (set, solved) = (&*set, &*solved);
        std::thread::scope(|scope| {
            for lane in lanes.iter_mut() {
                scope.spawn(move || {
                    let mut own = Bodies::new(position, &mut lane.velocity, inverse_mass);
                    for slot in lane.slots.clone() {
                        let view = island_view(set, solved[slot]);
                        project_met(
                            view,
                            &mut own,
                            &[],
                            dt,
                            settings,
                            &mut lane.scratch,
                            &mut lane.stats,
                            &mut lane.impulse,
                        );
                    }
                });
            }
            for slot in first {
                let view = island_view(set, solved[slot]);
                project_met(view, bodies, &[], dt, settings, scratch, stats, impulse);
            }
        });
        // Each lane's islands' velocities back; a pinned particle two islands share is
        // never written, so its copy is the value it had.
        for lane in lanes.iter() {
            for slot in lane.slots.clone() {
                for e in &set.edges[set.islands[solved[slot]].edges.clone()] {
                    for j in [e.a as usize, e.b as usize] {
                        bodies.velocity[j] = lane.velocity[j];
                    }
                    if e.edge != IslandEdge::GAP {
                        impulse[e.edge as usize] += lane.impulse[e.edge as usize];
                    }
                }
            }
            stats.merge(&lane.stats);
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
    ///
    /// A row between two units pushes the unit being solved alone, so it changes the
    /// momentum by its impulse; with `across_units` false such rows are left out (to
    /// the collision impulses, which push both sides). Speculative rows must be: they
    /// stop whole approaches, and at 1/600 two strands thrown at each other lost a
    /// third of their momentum to them. The contact loop's rows, after the impulses,
    /// only keep the edge projection from approaching again; their impulses are
    /// small, and without them the factories at 1/300 fell to the fail-safe at most
    /// steps.
    #[allow(clippy::too_many_arguments)]
    pub fn project_with_contacts(
        &mut self,
        island: &[u32],
        bodies: &mut Bodies,
        contacts: &[ContactRow],
        dt: f64,
        settings: &ProjectionSettings,
        sweeps: u32,
        across_units: bool,
        stats: &mut IterationStats,
        outcomes: &mut Vec<(u32, bool)>,
    ) -> f64 {
        outcomes.clear();
        let tolerance = settings.contact_tolerance / dt;
        self.form_units(island, contacts);
        let crosses_units = contacts.iter().any(|row| {
            let mut units = row
                .particles
                .iter()
                .filter_map(|&p| island_of(island, p as usize))
                .map(|i| self.units.find(i));
            units.next().is_some_and(|first| units.any(|u| u != first))
        });
        let mut shortfall = contacts
            .iter()
            .map(|row| row.target - row.normal_velocity(bodies.velocity))
            .fold(0.0, f64::max);
        for _ in 0..sweeps {
            let mut all_met = true;
            let mut start = 0;
            while start < self.members.len() {
                let unit = self.members[start].0;
                let end = start
                    + self.members[start..]
                        .iter()
                        .take_while(|t| t.0 == unit)
                        .count();
                // The unit's rows: every contact touching one of its islands, once.
                self.rows.clear();
                self.row_ids.clear();
                for &(_, member) in &self.members[start..end] {
                    let from = self.touched.partition_point(|t| t.0 < member);
                    for &(i, c) in &self.touched[from..] {
                        if i != member {
                            break;
                        }
                        self.row_ids.push(c);
                    }
                }
                self.row_ids.sort_unstable();
                self.row_ids.dedup();
                for &c in &self.row_ids {
                    let row = &contacts[c as usize];
                    let mut inside = || {
                        row.particles.iter().all(|&p| {
                            island_of(island, p as usize)
                                .is_none_or(|i| self.units.find(i) as u32 == unit)
                        })
                    };
                    if across_units || inside() {
                        self.rows.push(*row);
                    }
                }
                let rows = std::mem::take(&mut self.rows);
                let met = if end - start == 1 {
                    self.project_island(unit as usize, bodies, &rows, dt, settings, stats)
                } else {
                    self.project_group(start..end, bodies, &rows, dt, settings, stats)
                };
                all_met &= met;
                for &(_, member) in &self.members[start..end] {
                    match outcomes.iter_mut().find(|(i, _)| *i == member) {
                        Some(outcome) => outcome.1 = met,
                        None => outcomes.push((member, met)),
                    }
                }
                self.rows = rows;
                start = end;
            }
            shortfall = contacts
                .iter()
                .map(|row| row.target - row.normal_velocity(bodies.velocity))
                .fold(0.0, f64::max);
            // Each unit met its own contacts exactly; only contacts between units can
            // have been disturbed since. A unit that could not meet its rows against
            // the others' motion may meet them once the others have moved (a heavy
            // body stopped on a taut rope): it is tried again.
            if all_met && (!crosses_units || shortfall <= tolerance) {
                break;
            }
        }
        shortfall
    }

    /// Which islands `contacts` touch, and the units they are projected in: paths that
    /// touch each other are one unit, solved as one problem (their systems side by
    /// side, the contact rows between them eliminated together), as long as the unit's
    /// rows stay within [`UNIT_ROWS`]; a loop, tree or graph is a unit of its own. Units meet
    /// each other's contacts by the sweeps of block Gauss–Seidel.
    fn form_units(&mut self, island: &[u32], contacts: &[ContactRow]) {
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
        self.units.reset(self.set.islands.len());
        // Rows touching each unit (an upper bound: a row between two counts twice). The
        // unit's dense contact problem costs about the cube of its rows. Rows between
        // units are one-sided (see `project_with_contacts`): with all of them left out,
        // the factories at 1/600 took 263 and 2,377 fail-safe steps in 10 s with units
        // of 64 rows, 5 and 23 with 128.
        self.unit_rows.clear();
        self.unit_rows.resize(self.set.islands.len(), 0);
        for &(i, _) in &self.touched {
            self.unit_rows[i as usize] += 1;
        }
        let is_path = |i: usize| self.set.islands[i].kind == IslandKind::Path;
        for row in contacts {
            let mut paths = row
                .particles
                .iter()
                .filter_map(|&p| island_of(island, p as usize))
                .filter(|&i| is_path(i));
            if let Some(first) = paths.next() {
                for other in paths {
                    let (a, b) = (self.units.find(first), self.units.find(other));
                    let joined = self.unit_rows[a] + self.unit_rows[b];
                    if a != b && joined as usize <= UNIT_ROWS {
                        self.units.union(a, b);
                        self.unit_rows[a.min(b)] = joined;
                    }
                }
            }
        }
        self.members.clear();
        let mut previous = u32::MAX;
        for t in 0..self.touched.len() {
            let i = self.touched[t].0;
            if i != previous {
                let unit = self.units.find(i as usize) as u32;
                self.members.push((unit, i));
                previous = i;
            }
        }
        // A unit's islands in order, the unit named by its smallest island.
        self.members.sort_unstable();
    }

    /// Project the paths `self.members[members]` together with `contacts`: one open
    /// chain through all of them, consecutive paths joined by a locked gap edge that
    /// couples nothing; whether every path met its edges.
    fn project_group(
        &mut self,
        members: std::ops::Range<usize>,
        bodies: &mut Bodies,
        contacts: &[ContactRow],
        dt: f64,
        settings: &ProjectionSettings,
        stats: &mut IterationStats,
    ) -> bool {
        self.group_edges.clear();
        for &(_, member) in &self.members[members] {
            let edges = &self.set.edges[self.set.islands[member as usize].edges.clone()];
            if let (Some(last), Some(first)) = (self.group_edges.last(), edges.first()) {
                self.group_edges.push(IslandEdge::gap(last.b, first.a));
            }
            self.group_edges.extend_from_slice(edges);
        }
        let unit = IslandView::Chain(Chain {
            edges: &self.group_edges,
            closed: false,
        });
        project_met(
            unit,
            bodies,
            contacts,
            dt,
            settings,
            &mut self.scratch,
            stats,
            &mut self.impulse,
        )
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
        let Islands {
            set,
            scratch,
            impulse,
            ..
        } = self;
        let view = island_view(set, island);
        project_met(
            view, bodies, contacts, dt, settings, scratch, stats, impulse,
        )
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

/// The view of island `island` of `set`.
fn island_view(set: &IslandSet, island: usize) -> IslandView<'_> {
    let island = &set.islands[island];
    let edges = &set.edges[island.edges.clone()];
    match island.graph {
        Some(g) => IslandView::Graph(Graph {
            edges,
            layout: &set.graphs[g],
        }),
        None => IslandView::Chain(Chain {
            edges,
            closed: island.kind == IslandKind::Cycle,
        }),
    }
}

/// Project `view`, record the solve and its edges' impulses (into `impulse`, by
/// topology edge), and tell whether it met its edges.
#[allow(clippy::too_many_arguments)]
fn project_met(
    view: IslandView,
    bodies: &mut Bodies,
    contacts: &[ContactRow],
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
    stats: &mut IterationStats,
    impulse: &mut [f64],
) -> bool {
    let edges = match view {
        IslandView::Chain(Chain { edges, .. }) | IslandView::Graph(Graph { edges, .. }) => edges,
    };
    let outcome = project_island(view, bodies.reborrow(), contacts, dt, settings, scratch);
    for (e, j) in edges.iter().zip(scratch.edge_impulses(edges.len())) {
        if let Some(slot) = impulse.get_mut(e.edge as usize) {
            *slot += j;
        }
    }
    stats.record(&outcome);
    outcome.converged && !outcome.rejected && !outcome.singular
}

/// The most contact rows paths are joined into one unit for (an island alone may take
/// up to [`MAX_CONTACT_ROWS`](super::projection::MAX_CONTACT_ROWS)).
const UNIT_ROWS: usize = 128;

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
        ..
    } = &mut *state;
    let mut bodies = Bodies::new(position, velocity, inverse_mass);
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
