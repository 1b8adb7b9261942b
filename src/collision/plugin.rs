//! The Collide stage's systems (all but the contact loop) and the crossing check.

use bevy::math::DVec2;
use bevy::prelude::*;

use super::broad_phase::BroadPhase;
use super::broad_phase::BroadPhaseMethod;
use super::crossings::{Among, Crossings, count_crossings};
use super::impulses::{Collider, CollisionOutcome, ImpulseScratch, ImpulseSettings};
use super::still::{is_still, mostly_still, moving_edges};
use crate::metrics::{CrossedEdge, CrossingEvent, StrandMetrics, UnresolvedCollision, measure};
use crate::schedule::{CollideSet, StepSet, StrandsStep};
use crate::world::clock::SimulationClock;
use crate::world::config::{CollisionConfig, StrandsConfig};
use crate::world::state::ParticleState;
use crate::world::topology::Topology;

/// The Collide stage's buffers and the step's collision figures so far.
#[derive(Resource, Default, Debug)]
pub struct CollisionScratch {
    /// The impulse passes' buffers: pairs, contacts, impact zones.
    pub impulses: ImpulseScratch,
    /// What the step's collision processing has done so far.
    pub outcome: CollisionOutcome,
    /// Whether the pairs predate the proximity impulses' velocity change.
    stale: bool,
    crossing_pairs: Vec<(u32, u32)>,
    crossing_broad: BroadPhase,
    /// Which particles stood still this step, and which edges moved.
    crossing_still: Vec<bool>,
    crossing_moving: Vec<bool>,
    /// The crossings among still edges, and what they were counted for: a hash of the
    /// still particles and their positions (they do not move while it holds).
    still_crossings: Option<(u64, Crossings)>,
}

/// Proximity and collision impulses, the step's collision figures and the crossing check.
pub struct CollisionPlugin;

impl Plugin for CollisionPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<CollisionConfig>()
            .init_resource::<CollisionScratch>()
            .register_type::<CollisionConfig>()
            .add_systems(
                StrandsStep,
                (
                    proximity.in_set(CollideSet::Proximity),
                    impulses.in_set(CollideSet::Impulses),
                    account_collisions.in_set(CollideSet::Account),
                    check_crossings.in_set(StepSet::Measure).after(measure),
                ),
            );
    }
}

impl CollisionConfig {
    /// The settings of one step's impulses, with `threads` for the candidate search.
    pub fn impulse_settings(&self, threads: usize) -> ImpulseSettings {
        ImpulseSettings {
            threads,
            thickness: self.thickness,
            friction: self.friction,
            restitution: self.restitution,
            max_iterations: self.max_iterations,
            separation: self.separation,
            broad_phase: self.broad_phase,
        }
    }
}

/// The packed state, the edges and the buffers as a [`Collider`] for one step.
pub fn collider<'a>(
    state: &'a mut ParticleState,
    topology: &'a Topology,
    settings: &'a ImpulseSettings,
    dt: f64,
    scratch: &'a mut ImpulseScratch,
) -> Collider<'a> {
    let ParticleState {
        position,
        velocity,
        mass,
        inverse_mass,
        in_contact,
        ..
    } = state;
    Collider {
        edges: &topology.edges,
        version: topology.version,
        position,
        velocity,
        mass,
        inverse_mass,
        groups: &topology.island,
        solid: &topology.solid,
        in_contact,
        settings,
        dt,
        scratch,
    }
}

/// Proximity sub-stage: forget the previous step's contacts, find the candidate pairs,
/// push apart those that would end the step closer than the thickness.
pub fn proximity(
    config: Res<CollisionConfig>,
    step: Res<StrandsConfig>,
    topology: Res<Topology>,
    mut state: ResMut<ParticleState>,
    mut scratch: ResMut<CollisionScratch>,
) {
    state.in_contact.fill(false);
    if !config.enabled {
        return;
    }
    let scratch = &mut *scratch;
    scratch.impulses.begin_step(state.len());
    let settings = config.impulse_settings(step.worker_threads());
    let mut collider = collider(
        &mut state,
        &topology,
        &settings,
        step.dt,
        &mut scratch.impulses,
    );
    if std::mem::take(&mut collider.scratch.speculated_step) {
        // The contact solve kept the cushion, inside the exact projection: its
        // contacts are the step's, and no impulse is needed.
        collider.adopt_speculated();
        scratch.outcome = CollisionOutcome::default();
        scratch.stale = true;
        return;
    }
    collider.find_pairs();
    let impulses = collider.proximity_pass();
    scratch.outcome = CollisionOutcome {
        impulses,
        ..default()
    };
    scratch.stale = impulses > 0;
}

/// Impulses sub-stage: detection and impulses until a pass is clean, then the fail-safe.
pub fn impulses(
    config: Res<CollisionConfig>,
    step: Res<StrandsConfig>,
    topology: Res<Topology>,
    mut state: ResMut<ParticleState>,
    mut scratch: ResMut<CollisionScratch>,
) {
    if !config.enabled {
        return;
    }
    let scratch = &mut *scratch;
    let settings = config.impulse_settings(step.worker_threads());
    let mut collider = collider(
        &mut state,
        &topology,
        &settings,
        step.dt,
        &mut scratch.impulses,
    );
    let crossings = collider.resolve_crossings(scratch.stale);
    // The proximity impulses were counted first.
    let proximity = scratch.outcome.impulses;
    scratch.outcome = crossings;
    scratch.outcome.impulses += proximity;
}

/// Account sub-stage: the step's collision figures into the metrics. A collision left
/// unresolved is logged with its particles at once.
pub fn account_collisions(
    config: Res<CollisionConfig>,
    scratch: Res<CollisionScratch>,
    state: Res<ParticleState>,
    clock: Res<SimulationClock>,
    mut metrics: ResMut<StrandMetrics>,
) {
    if !config.enabled {
        return;
    }
    let total = scratch.outcome;
    metrics.contacts += scratch.impulses.contacts.len() as u64;
    metrics.collisions += total.impulses;
    metrics.collisions_last_step = total.impulses;
    metrics.failsafe_steps += u64::from(total.failsafe);
    metrics.unresolved_collisions += total.unresolved as u64;
    if let Some((particles, driven)) = total.first_unresolved {
        let event = UnresolvedCollision {
            step: clock.steps + 1,
            particles: particles.map(|i| state.entity[i as usize]),
            positions: particles.map(|i| state.position[i as usize]),
            driven_by: driven.map(|i| state.entity[i as usize]),
        };
        warn!(
            "bevy_strands: step {}: {} collision(s) left unresolved, kinematic particles driven \
             through each other; the first: point {} against the edge {}–{}, driven by {:?}",
            event.step,
            total.unresolved,
            event.particles[0],
            event.particles[1],
            event.particles[2],
            event.driven_by
        );
        metrics.last_unresolved = Some(event);
    }
}

/// The Measure stage's crossing check (checked mode only). The first crossing is
/// recorded with its edges and logged as an error.
pub fn check_crossings(
    config: Res<CollisionConfig>,
    step: Res<StrandsConfig>,
    topology: Res<Topology>,
    state: Res<ParticleState>,
    clock: Res<SimulationClock>,
    mut scratch: ResMut<CollisionScratch>,
    mut metrics: ResMut<StrandMetrics>,
) {
    if !config.check_crossings {
        return;
    }
    let CollisionScratch {
        impulses,
        crossing_pairs,
        crossing_broad,
        crossing_still,
        crossing_moving,
        still_crossings,
        ..
    } = &mut *scratch;
    // Where much stands still (a sleeping pile), the pairs with a moving edge are
    // counted every step and those among still edges only when the still set changes.
    // (A particle with no velocity after the step had no displacement over it.)
    crossing_still.clear();
    crossing_still
        .extend((0..state.len()).map(|i| is_still(&state.inverse_mass, &state.velocity, i)));
    let still = crossing_still.iter().filter(|&&s| s).count();
    let grid = config.broad_phase == BroadPhaseMethod::Grid;
    let threads = step.worker_threads();
    let crossings = if grid && mostly_still(still, crossing_still.len()) {
        moving_edges(&topology.edges, crossing_still, crossing_moving);
        let key = still_key(crossing_still, &state.position, topology.version);
        let mut count = |among| {
            count_crossings(
                &topology.edges,
                &state.position,
                crossing_broad,
                Some(impulses.grid_mut()),
                among,
                config.broad_phase,
                threads,
                crossing_pairs,
            )
        };
        let still = match still_crossings {
            Some((k, counted)) if *k == key => *counted,
            _ => {
                let counted = count(Among::Still(crossing_moving));
                *still_crossings = Some((key, counted));
                counted
            }
        };
        let moving = count(Among::Moving(crossing_moving));
        Crossings {
            pairs: moving.pairs + still.pairs,
            first: match (moving.first, still.first) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            },
        }
    } else {
        count_crossings(
            &topology.edges,
            &state.position,
            crossing_broad,
            Some(impulses.grid_mut()),
            Among::All,
            config.broad_phase,
            threads,
            crossing_pairs,
        )
    };
    metrics.crossing_pairs_last_step = crossings.pairs;
    *metrics.edge_crossings.get_or_insert(0) += u64::from(crossings.pairs > 0);
    if let (Some((j, k)), None) = (crossings.first, &metrics.first_crossing) {
        let event = CrossingEvent {
            step: clock.steps,
            time: clock.time,
            pairs: crossings.pairs,
            edges: [j, k].map(|e| CrossedEdge::of(e as usize, &topology, &state)),
        };
        error!(
            "bevy_strands: edges crossed at step {} (t = {:.6} s): {:?}",
            event.step, event.time, event.edges
        );
        metrics.first_crossing = Some(event);
    }
}

/// A hash of which particles stand still and where (FNV-1a over their bits), with the
/// topology's version: while it holds, the still edges are where they were.
fn still_key(still: &[bool], position: &[DVec2], version: u64) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64 ^ version;
    let mut mix = |x: u64| {
        hash ^= x;
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    };
    for (i, (&s, p)) in still.iter().zip(position).enumerate() {
        if s {
            mix(i as u64);
            mix(p.x.to_bits());
            mix(p.y.to_bits());
        }
    }
    hash
}
