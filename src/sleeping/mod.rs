//! Sleeping: strands at rest cost nothing until something moving reaches them.
//!
//! Every tick ends with a tally: each unit (strands joined by shared particles, or a
//! loose particle; see [`units`]) whose every particle is still within
//! [`SleepConfig::drift`](crate::world::config::SleepConfig) of where its rest began
//! adds the tick to its rest time, any other starts again from zero. At the start of
//! the next tick, before the topology rebuild, a unit that has rested
//! [`SleepConfig::time`](crate::world::config::SleepConfig), and whose awake
//! neighbours in contact (the tick's contacts) have too, goes to sleep:
//! its particles get the [`Sleeping`] marker, which the topology reads as a pin and the
//! gather as zero velocity, so a sleeping strand keeps its positions exactly, takes no
//! part in the projection or the contact solve, and is collided against as a body of
//! infinite mass. A sleeping unit wakes, its marker removed, when
//!
//! - something moving (faster than the sleep speed: a strand, a collider's outline, a
//!   body's) will come within two thicknesses of it over the tick ([`reach`]),
//! - a particle of it is written to (position, velocity, mass, external force) or given
//!   a tether, or loses its marker, since the last tick, or
//! - one of its kinematic particles (an anchor) moves, or
//! - a particle within reach of it is despawned (what it rested on is gone).
//!
//! Waking is per unit: a strand something touches wakes alone, and its sleeping
//! neighbours hold still until something moving reaches them in turn.
//!
//! Imports: [`crate::model`], [`crate::collision`] (the broad phase's grid for the reach
//! test), [`crate::metrics`], [`crate::world`], [`crate::schedule`].

pub mod reach;
pub mod units;

use bevy::ecs::change_detection::Tick;
use bevy::ecs::system::SystemChangeTick;
use bevy::math::DVec2;
use bevy::prelude::*;

use crate::collision::plugin::{CollisionScratch, check_crossings};
use crate::metrics::StrandMetrics;
use crate::model::union_find::UnionFind;
use crate::schedule::{StepSet, StrandsStep, StrandsTick, TickSet, stepping};
use crate::world::config::{CollisionConfig, StrandsConfig};
use crate::world::particle::{
    ExternalForce, Frozen, Kinematic, Mass, Particle, Pinned, Position, Sleeping, SolverIndex,
    Tether, Velocity,
};
use crate::world::state::{ParticleState, copy_buffer};
use crate::world::topology::Topology;
use reach::{ReachInput, ReachScratch, find_reached};
use units::{NO_UNIT, Units, on_the_move, pressed_units, rest, units_to_sleep};

/// Puts resting strands to sleep and wakes them.
pub struct SleepPlugin;

impl Plugin for SleepPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<SleepState>()
            .register_type::<Sleeping>()
            .add_systems(
                StrandsTick,
                (
                    sleep_and_wake.in_set(TickSet::Sleep),
                    refresh_units.in_set(TickSet::Gather),
                    tally.after(TickSet::Writeback).run_if(stepping),
                ),
            )
            .add_systems(
                StrandsStep,
                collect_contacts
                    .in_set(StepSet::Measure)
                    .before(check_crossings),
            );
    }
}

/// The units, their rest times and which sleep.
#[derive(Resource, Default, Debug)]
pub struct SleepState {
    /// The topology version the units were found for.
    version: Option<u64>,
    units: Units,
    /// Each unit's first particle's entity: rest times follow it across rebuilds.
    keys: Vec<Entity>,
    rested: Vec<f64>,
    /// Where each unit's particles were when its rest began (as `units.members`).
    anchors: Vec<DVec2>,
    /// How far each unit's particles are from their anchors (at most).
    strayed: Vec<f64>,
    asleep: Vec<bool>,
    restless: Vec<bool>,
    /// Pairs of units in contact since the last tick began.
    contacts: Vec<(u32, u32)>,
    /// The change tick after the last write-back: later writes are the user's.
    synced: Option<Tick>,
    sets: UnionFind,
    reach: ReachScratch,
    moving: Vec<bool>,
    displacement: Vec<DVec2>,
    woken: Vec<bool>,
    reached: Vec<bool>,
    /// Sleeping units an awake, unrested one touched: they wake at any speed.
    pressed: Vec<bool>,
    sleepers: Vec<u32>,
    target: Vec<bool>,
    blocked: Vec<bool>,
}

impl SleepState {
    /// Whether packed particle `i` belongs to a sleeping unit.
    pub fn is_asleep(&self, i: usize) -> bool {
        self.units
            .of
            .get(i)
            .is_some_and(|&u| u != NO_UNIT && self.asleep[u as usize])
    }

    /// Whether packed particle `i` has settled: its unit sleeps or has rested `time`
    /// (a wall's particle, in no unit, always has).
    pub fn settled(&self, i: usize, time: f64) -> bool {
        match self.units.of.get(i) {
            Some(&u) if u != NO_UNIT => {
                let u = u as usize;
                self.asleep[u] || self.rested[u] >= time
            }
            _ => true,
        }
    }

    /// Particles in sleeping units.
    pub fn asleep_particles(&self) -> usize {
        (0..self.units.len())
            .filter(|&u| self.asleep[u])
            .map(|u| self.units.particles(u).len())
            .sum()
    }

    /// Sleeping units, and units in all.
    pub fn asleep_units(&self) -> (usize, usize) {
        (self.asleep.iter().filter(|&&a| a).count(), self.units.len())
    }
}

/// After a rebuild: the units of the new topology, each taking the rest time its first
/// particle's unit had, asleep when its particles carry the marker.
fn refresh_units(
    topology: Res<Topology>,
    state: Res<ParticleState>,
    mut sleep: ResMut<SleepState>,
    sleeping: Query<(), With<Sleeping>>,
) {
    if sleep.version == Some(topology.version) {
        return;
    }
    let sleep = &mut *sleep;
    let count = topology.pinned.len().min(state.entity.len());
    // Each old unit's rest time and anchors, by its key.
    let old: bevy::platform::collections::HashMap<Entity, (f64, usize, usize)> =
        (0..sleep.keys.len())
            .map(|u| {
                let (start, end) = (sleep.units.start[u], sleep.units.start[u + 1]);
                (
                    sleep.keys[u],
                    (sleep.rested[u], start as usize, end as usize),
                )
            })
            .collect();
    let old_anchors = std::mem::take(&mut sleep.anchors);
    sleep
        .units
        .find(count, &topology.edges, &topology.solid, &mut sleep.sets);
    let units = &sleep.units;
    sleep.keys.clear();
    sleep.rested.clear();
    sleep.asleep.clear();
    for u in 0..units.len() {
        let members = units.particles(u);
        let key = state.entity[members[0] as usize];
        sleep.keys.push(key);
        // The same unit (its first particle and its size) keeps its rest.
        match old.get(&key) {
            Some(&(rested, start, end)) if end - start == members.len() => {
                sleep.rested.push(rested);
                sleep.anchors.extend_from_slice(&old_anchors[start..end]);
            }
            _ => {
                sleep.rested.push(0.0);
                sleep
                    .anchors
                    .extend(members.iter().map(|&i| state.position[i as usize]));
            }
        }
        sleep.asleep.push(
            members
                .iter()
                .any(|&i| sleeping.contains(state.entity[i as usize])),
        );
    }
    sleep.restless.clear();
    sleep.restless.resize(units.len(), false);
    sleep.strayed.clear();
    sleep.strayed.resize(units.len(), 0.0);
    sleep.contacts.clear();
    sleep.version = Some(topology.version);
}

/// Each step: the pairs of units its contacts joined.
fn collect_contacts(
    config: Res<StrandsConfig>,
    scratch: Res<CollisionScratch>,
    topology: Res<Topology>,
    mut sleep: ResMut<SleepState>,
) {
    if !config.sleep.enabled || sleep.version != Some(topology.version) {
        return;
    }
    let sleep = &mut *sleep;
    for contact in &scratch.impulses.contacts {
        let Some(edge) = topology.edges.get(contact.edge as usize) else {
            continue;
        };
        let unit = |i: u32| sleep.units.of.get(i as usize).copied().unwrap_or(NO_UNIT);
        let (a, b) = (unit(contact.p), unit(edge.a));
        if a != NO_UNIT && b != NO_UNIT && a != b {
            sleep.contacts.push((a.min(b), a.max(b)));
        }
    }
}

/// The end of a tick: each awake unit's rest time, and the mark after which writes are
/// the user's.
pub(crate) fn tally(
    config: Res<StrandsConfig>,
    topology: Res<Topology>,
    state: Res<ParticleState>,
    mut sleep: ResMut<SleepState>,
    mut metrics: ResMut<StrandMetrics>,
    ticks: SystemChangeTick,
) {
    let sleep = &mut *sleep;
    sleep.synced = Some(ticks.this_run());
    if !config.sleep.enabled || sleep.version != Some(topology.version) {
        metrics.asleep_particles = 0;
        return;
    }
    let tick = config.tick_seconds();
    let drift = config.sleep.drift;
    rest(
        &sleep.units,
        &state.position,
        &sleep.asleep,
        drift,
        tick,
        &mut sleep.anchors,
        &mut sleep.rested,
        &mut sleep.strayed,
    );
    metrics.asleep_particles = sleep.asleep_particles();
}

type ParticleQuery<'w, 's> = Query<
    'w,
    's,
    (
        &'static SolverIndex,
        Ref<'static, Position>,
        Ref<'static, Velocity>,
        Ref<'static, Mass>,
        Option<Ref<'static, ExternalForce>>,
        Has<Sleeping>,
        Has<Pinned>,
        Has<Kinematic>,
        Has<Frozen>,
        Has<Tether>,
    ),
    With<Particle>,
>;

/// The start of a tick: wake what was written to or will be reached, put to sleep the
/// units that have rested long enough and that nothing moving will reach.
#[allow(clippy::too_many_arguments)]
fn sleep_and_wake(
    config: Res<StrandsConfig>,
    collision: Res<CollisionConfig>,
    topology: Res<Topology>,
    state: Res<ParticleState>,
    mut sleep: ResMut<SleepState>,
    mut metrics: ResMut<StrandMetrics>,
    particles: ParticleQuery,
    mut removed: RemovedComponents<Particle>,
    ticks: SystemChangeTick,
    mut commands: Commands,
) {
    let sleep = &mut *sleep;
    let fresh = sleep.version == Some(topology.version);
    if !config.sleep.enabled || !fresh {
        if !config.sleep.enabled {
            // Switched off: everything asleep wakes.
            for u in 0..sleep.asleep.len() {
                if sleep.asleep[u] {
                    wake(sleep, u, &state, &mut commands);
                    metrics.wakes += 1;
                }
            }
        }
        sleep.contacts.clear();
        return;
    }
    let n = sleep.units.of.len();
    let tick = config.tick_seconds();
    let speed = config.sleep.speed;
    let written = |changed: Tick| {
        sleep
            .synced
            .is_some_and(|synced| changed.is_newer_than(synced, ticks.this_run()))
    };
    sleep.moving.clear();
    sleep.moving.resize(n, false);
    sleep.displacement.clear();
    sleep.displacement.resize(n, DVec2::ZERO);
    sleep.woken.clear();
    sleep.woken.resize(sleep.units.len(), false);
    sleep.restless.fill(false);
    let fall = 0.5 * config.gravity * tick * tick;
    for (index, position, velocity, mass, force, asleep, pinned, kinematic, frozen, tether) in
        &particles
    {
        let Some(i) = index.get().filter(|&i| i < n) else {
            continue;
        };
        let u = sleep.units.of[i];
        let held = pinned || frozen;
        let v = if held { DVec2::ZERO } else { velocity.0 };
        let free = !(held || kinematic || asleep);
        let unit_asleep = u != NO_UNIT && sleep.asleep[u as usize];
        if unit_asleep {
            let touched = written(position.last_changed())
                || written(velocity.last_changed())
                || written(mass.last_changed())
                || force.is_some_and(|f| written(f.last_changed()))
                || tether
                || free
                || (kinematic && v != DVec2::ZERO);
            sleep.woken[u as usize] |= touched;
        } else {
            if u != NO_UNIT {
                sleep.restless[u as usize] |= tether;
            }
            sleep.displacement[i] = tick * v + if free { fall } else { DVec2::ZERO };
            // A driven particle (an anchor, a body's outline) moves at any speed: a
            // sleeping strand does not answer it, so it must wake first. A free one
            // moves when faster than the sleep speed and its unit is on the move: a
            // resting unit trembles, it does not go anywhere.
            sleep.moving[i] = if kinematic {
                v != DVec2::ZERO
            } else {
                let on_move = u == NO_UNIT || {
                    let u = u as usize;
                    on_the_move(sleep.rested[u], sleep.strayed[u], speed)
                };
                on_move && v.length_squared() > speed * speed
            };
        }
    }

    // A despawned particle lets go of what rested on it: where it lay counts as moving
    // this tick (its slot still holds its last position until the rebuild).
    for entity in removed.read() {
        if let Some(&i) = topology.index.get(&entity).filter(|&&i| (i as usize) < n) {
            sleep.moving[i as usize] = true;
        }
    }

    // The units ready to sleep, then what something moving reaches among them and
    // the sleeping.
    sleep.sleepers.clear();
    units_to_sleep(
        &sleep.asleep,
        &sleep.restless,
        &sleep.rested,
        config.sleep.time,
        &sleep.contacts,
        &mut sleep.blocked,
        &mut sleep.sleepers,
    );
    pressed_units(
        &sleep.asleep,
        &sleep.rested,
        config.sleep.time,
        &sleep.contacts,
        &mut sleep.pressed,
    );
    sleep.contacts.clear();
    let mut target = std::mem::take(&mut sleep.target);
    copy_buffer(&mut target, &sleep.asleep);
    for &u in &sleep.sleepers {
        target[u as usize] = true;
    }
    for (u, target) in target.iter_mut().enumerate() {
        *target &= !sleep.woken[u];
    }
    sleep.reached.clear();
    sleep.reached.resize(sleep.units.len(), false);
    let input = ReachInput {
        edges: &topology.edges,
        unit_of: &sleep.units.of,
        target: &target,
        moving: &sleep.moving,
        position: &state.position[..n],
        displacement: &sleep.displacement,
        reach: 2.0 * collision.thickness,
        threads: config.worker_threads(),
    };
    find_reached(&input, &mut sleep.reach, &mut sleep.reached);
    sleep.target = target;

    for u in 0..sleep.units.len() {
        if sleep.asleep[u] && (sleep.woken[u] || sleep.reached[u] || sleep.pressed[u]) {
            let only_pressed = !(sleep.woken[u] || sleep.reached[u]);
            wake(sleep, u, &state, &mut commands);
            if only_pressed {
                // It was at rest and a touch has not moved it: it counts as rested, so
                // it presses on its own sleeping neighbours only once it moves.
                sleep.rested[u] = config.sleep.time;
            }
            metrics.wakes += 1;
        }
    }
    for k in 0..sleep.sleepers.len() {
        let u = sleep.sleepers[k] as usize;
        if sleep.reached[u] {
            continue;
        }
        for &i in sleep.units.particles(u) {
            let i = i as usize;
            // Pinned and kinematic particles stay as they are; the unit wakes if a
            // kinematic one moves.
            if !topology.pinned[i] {
                commands.entity(state.entity[i]).try_insert(Sleeping);
            }
        }
        sleep.asleep[u] = true;
        metrics.sleeps += 1;
    }
}

/// Wake unit `u`: its markers removed, its rest time from zero.
fn wake(sleep: &mut SleepState, u: usize, state: &ParticleState, commands: &mut Commands) {
    for &i in sleep.units.particles(u) {
        if let Some(&entity) = state.entity.get(i as usize) {
            commands.entity(entity).try_remove::<Sleeping>();
        }
    }
    sleep.asleep[u] = false;
    sleep.rested[u] = 0.0;
}
