//! Figures of merit, updated by the Measure stage at the end of every step.
//!
//! The headline figure is the maximum relative length error `|ℓ − L| / L` over every
//! edge that should keep its length (every edge but the static ones) at the end of
//! every step. It is also kept separately for edges none of whose particles took part
//! in a contact that step, because contact impulses come after the constraint solve.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::constraints::projection::ProjectionOutcome;
use crate::model::edge::measure_length_errors;
use crate::schedule::{StepSet, StrandsStep, StrandsTick, TickSet, stepping};
use crate::world::clock::SimulationClock;
use crate::world::state::{ParticleState, copy_buffer};
use crate::world::topology::{Topology, rebuild_topology};

/// The figures of merit: length errors every step, counts after every rebuild, and the
/// length-error history when one is kept.
pub struct MetricsPlugin;

impl Plugin for MetricsPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<StrandMetrics>()
            .add_systems(
                StrandsTick,
                (
                    count_elements
                        .in_set(TickSet::Topology)
                        .after(rebuild_topology),
                    begin_tick.in_set(TickSet::Gather).run_if(stepping),
                    record_length_error_history.in_set(TickSet::Writeback),
                ),
            )
            .add_systems(StrandsStep, measure.in_set(StepSet::Measure));
    }
}

/// Running totals of a constraint solver's iterations.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct IterationStats {
    /// Island solves performed.
    pub solves: u64,
    /// Iterations summed over all solves.
    pub iterations: u64,
    /// Most iterations any one solve took.
    pub max: u32,
    /// Solves that stopped at the iteration cap without meeting the tolerance.
    pub capped: u64,
    /// Solves whose corrections were too large to apply and were dropped.
    pub rejected: u64,
    /// Contact projections whose rows the contact Newton solved (the rest were swept).
    /// (Snapshots from before it read 0.)
    #[cfg_attr(feature = "serde", serde(default))]
    pub newton_solves: u64,
    /// The contact Newton's sparse factorizations.
    #[cfg_attr(feature = "serde", serde(default))]
    pub factorizations: u64,
    /// Contact projections whose sweeps left a squeezed pair short and that the
    /// contact Newton solved again (counted in `newton_solves` too).
    #[cfg_attr(feature = "serde", serde(default))]
    pub escalated: u64,
    /// Solves whose island was stepped again in substeps after one projection failed.
    #[cfg_attr(feature = "serde", serde(default))]
    pub restepped: u64,
    /// The substeps those re-stepped solves took, in all.
    #[cfg_attr(feature = "serde", serde(default))]
    pub substeps: u64,
}

impl StrandMetrics {
    /// Become a copy of `other`, reusing this one's buffer of edge errors.
    pub fn copy_from(&mut self, other: &StrandMetrics) {
        let mut errors = std::mem::take(&mut self.relative_length_error);
        copy_buffer(&mut errors, &other.relative_length_error);
        *self = StrandMetrics {
            relative_length_error: errors,
            ..*other
        };
    }
}

impl IterationStats {
    /// Record one island solve.
    pub fn record(&mut self, outcome: &ProjectionOutcome) {
        self.solves += 1;
        self.iterations += outcome.iterations as u64;
        self.max = self.max.max(outcome.iterations);
        self.rejected += u64::from(outcome.rejected);
        self.capped += u64::from(!outcome.converged && !outcome.rejected);
        self.restepped += u64::from(outcome.restepped);
        self.substeps += u64::from(outcome.substeps);
    }

    /// Add the counts of `other` (solves recorded elsewhere, e.g. on another thread).
    pub fn merge(&mut self, other: &IterationStats) {
        self.solves += other.solves;
        self.iterations += other.iterations;
        self.max = self.max.max(other.max);
        self.capped += other.capped;
        self.rejected += other.rejected;
        self.newton_solves += other.newton_solves;
        self.factorizations += other.factorizations;
        self.escalated += other.escalated;
        self.restepped += other.restepped;
        self.substeps += other.substeps;
    }

    /// Record a contact projection's factorizations (none: its rows were swept).
    pub fn record_factorizations(&mut self, factorizations: u32) {
        self.newton_solves += u64::from(factorizations > 0);
        self.factorizations += u64::from(factorizations);
    }

    /// Mean iterations per solve (0 before any solve).
    pub fn mean(&self) -> f64 {
        if self.solves == 0 {
            0.0
        } else {
            self.iterations as f64 / self.solves as f64
        }
    }
}

/// Metrics of the running simulation.
#[derive(Resource, Default, Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default)
)]
pub struct StrandMetrics {
    /// Current `|ℓ − L| / L` of every edge of [`Topology::edges`] (0 for static ones).
    #[cfg_attr(feature = "serde", serde(skip))]
    pub relative_length_error: Vec<f64>,
    /// Largest relative length error at the end of the latest step.
    pub max_rel_length_error_now: f64,
    /// Largest relative length error at the end of any step.
    pub max_rel_length_error: f64,
    /// As `max_rel_length_error_now`, over edges away from contacts.
    pub max_rel_length_error_free_now: f64,
    /// As `max_rel_length_error`, over edges away from contacts.
    pub max_rel_length_error_free: f64,
    /// Largest relative length error over the steps of the latest tick.
    pub tick_max_rel_length_error: f64,
    /// As `tick_max_rel_length_error`, over edges away from contacts.
    pub tick_max_rel_length_error_free: f64,
    /// Simulated particles.
    pub particles: usize,
    /// Simulated strands.
    pub strands: usize,
    /// Edges that are not static.
    pub edges: usize,
    /// Edges kept at rest length by the constraint solver.
    pub constrained_edges: usize,
    /// Constraint projection iterations per island solve (the Constrain stage).
    pub projection: IterationStats,
    /// Re-projections of islands in contact (the contact loop).
    pub contact_projection: IterationStats,
    /// Point–edge contacts met, summed over steps: each step, every pair that the
    /// contact solve held apart with an impulse or that a collision impulse pushed
    /// apart, once.
    pub contacts: u64,
    /// Collision impulses applied (after the contact solve: what it left to the
    /// continuous detection).
    pub collisions: u64,
    /// Collision impulses applied in the latest step.
    pub collisions_last_step: u64,
    /// Steps that needed the collision fail-safe.
    pub failsafe_steps: u64,
    /// Steps that would have ended in the fail-safe and were taken again as two halves
    /// ([`StrandsConfig::max_step_halvings`](crate::world::config::StrandsConfig)).
    #[cfg_attr(feature = "serde", serde(default))]
    pub halved_steps: u64,
    /// Steps taken in parts from the start because the one before was hard
    /// ([`StrandsConfig::max_split_ahead`](crate::world::config::StrandsConfig)).
    #[cfg_attr(feature = "serde", serde(default))]
    pub split_steps: u64,
    /// Steps whose collisions still needed impulses after the last re-projection, so
    /// that edges next to those contacts end the step as the impulses left them.
    pub contact_unsettled_steps: u64,
    /// Collisions the fail-safe could not resolve (only kinematic particles driven
    /// into each other can cause these).
    pub unresolved_collisions: u64,
    /// The latest of them, with its particles.
    pub last_unresolved: Option<UnresolvedCollision>,
    /// Intersecting edge pairs at the end of the latest checked step.
    pub crossing_pairs_last_step: usize,
    /// Step ends at which two edges sharing no particle intersected; `None` when not
    /// checked.
    pub edge_crossings: Option<u64>,
    /// The first step end at which edges crossed, with the edges (checked mode).
    pub first_crossing: Option<CrossingEvent>,
    /// Particles in sleeping strands at the end of the latest tick.
    #[cfg_attr(feature = "serde", serde(default))]
    pub asleep_particles: usize,
    /// Units (strands joined by shared particles) put to sleep, in all.
    #[cfg_attr(feature = "serde", serde(default))]
    pub sleeps: u64,
    /// Units woken, in all.
    #[cfg_attr(feature = "serde", serde(default))]
    pub wakes: u64,
}

/// A collision nothing could resolve: a point driven into an edge by kinematic
/// particles (pinned and moving), so the step may end with them crossed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct UnresolvedCollision {
    /// The step it happened in (1 for the first step).
    pub step: u64,
    /// The point, and the two particles of the edge.
    pub particles: [Entity; 3],
    /// Their positions at the start of the step.
    pub positions: [DVec2; 3],
    /// The moving pinned particle that drove them together, if one did.
    pub driven_by: Option<Entity>,
}

/// Two edges found crossing at the end of a step: where and when, and which particles.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CrossingEvent {
    /// The step that ended with the crossing (1 for the first step).
    pub step: u64,
    /// Simulated time at its end.
    pub time: f64,
    /// How many pairs crossed at that step end.
    pub pairs: usize,
    /// The two edges of the first pair.
    pub edges: [CrossedEdge; 2],
}

/// One edge of a crossing pair.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CrossedEdge {
    /// The strand the edge belongs to.
    pub strand: Entity,
    /// The edge's number along its strand.
    pub edge: u32,
    /// Its two particles.
    pub particles: [Entity; 2],
    /// Their positions.
    pub positions: [DVec2; 2],
}

impl CrossedEdge {
    /// Edge `k` of the topology, as the particles of `state` place it.
    pub fn of(k: usize, topology: &Topology, state: &ParticleState) -> Self {
        let edge = &topology.edges[k];
        let record = &topology.strands[edge.strand as usize];
        let (a, b) = (edge.a as usize, edge.b as usize);
        CrossedEdge {
            strand: record.entity,
            edge: (k - record.edges.start) as u32,
            particles: [state.entity[a], state.entity[b]],
            positions: [state.position[a], state.position[b]],
        }
    }
}

impl StrandMetrics {
    /// Forget the maxima and counters (keeps the counts of the current topology).
    pub fn reset_figures(&mut self) {
        *self = Self {
            relative_length_error: std::mem::take(&mut self.relative_length_error),
            particles: self.particles,
            strands: self.strands,
            edges: self.edges,
            constrained_edges: self.constrained_edges,
            edge_crossings: self.edge_crossings.map(|_| 0),
            ..Self::default()
        };
    }
}

/// The Measure stage's length figures.
pub fn measure(
    topology: Res<Topology>,
    state: Res<ParticleState>,
    mut metrics: ResMut<StrandMetrics>,
) {
    let metrics = &mut *metrics;
    if metrics.relative_length_error.len() != topology.edges.len() {
        metrics
            .relative_length_error
            .resize(topology.edges.len(), 0.0);
    }
    let (all, free) = measure_length_errors(
        &topology.edges,
        &state.position,
        &state.in_contact,
        &mut metrics.relative_length_error,
    );
    metrics.max_rel_length_error_now = all;
    metrics.max_rel_length_error_free_now = free;
    metrics.max_rel_length_error = metrics.max_rel_length_error.max(all);
    metrics.max_rel_length_error_free = metrics.max_rel_length_error_free.max(free);
    metrics.tick_max_rel_length_error = metrics.tick_max_rel_length_error.max(all);
    metrics.tick_max_rel_length_error_free = metrics.tick_max_rel_length_error_free.max(free);
}

/// One tick's length errors, for plots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorSample {
    /// Simulated time at the end of the tick.
    pub time: f64,
    /// Largest relative length error over the tick's steps.
    pub all: f64,
    /// The same over edges away from contacts.
    pub free: f64,
}

/// The length error of every tick, recorded while this resource exists (insert it to
/// plot; it grows by one sample per tick).
#[derive(Resource, Default, Debug, Clone)]
pub struct LengthErrorHistory {
    /// One sample per tick, oldest first.
    pub samples: Vec<ErrorSample>,
}

/// Append the tick's sample to the history, if one is kept.
pub fn record_length_error_history(
    metrics: Res<StrandMetrics>,
    clock: Res<SimulationClock>,
    history: Option<ResMut<LengthErrorHistory>>,
) {
    if let Some(mut history) = history {
        history.samples.push(ErrorSample {
            time: clock.time,
            all: metrics.tick_max_rel_length_error,
            free: metrics.tick_max_rel_length_error_free,
        });
    }
}

/// Forget the previous tick's maxima (start of a tick that steps).
pub fn begin_tick(mut metrics: ResMut<StrandMetrics>) {
    metrics.tick_max_rel_length_error = 0.0;
    metrics.tick_max_rel_length_error_free = 0.0;
}

/// Refresh the counts after a topology rebuild.
pub fn count_elements(
    topology: Res<Topology>,
    state: Res<ParticleState>,
    mut metrics: ResMut<StrandMetrics>,
) {
    if topology.is_changed() {
        metrics.particles = state.len();
        metrics.strands = topology.strands.len();
        metrics.edges = topology.dynamic_edge_count();
        metrics.constrained_edges = topology.edges.iter().filter(|e| e.constrained).count();
    }
}
