//! The finiteness guard: a non-finite force, velocity or position is caught after the
//! stage that made it, and the constraint island it appeared in is frozen at its last
//! finite state instead of spreading NaN to everything it touches.
//!
//! After each stage of a step one array is scanned — the one that stage writes:
//! forces after Forces, velocities after Predict, Constrain and Collide, positions after
//! Integrate. At the first non-finite value the island of every bad particle (the whole
//! solved island, or the particle alone if it is in none) goes back to where it was at
//! the start of the step, with zero velocity, and stays there for the rest of the tick;
//! at the end of the tick its particles get the [`Frozen`] marker, which the topology
//! treats as a pin with zero velocity. A [`NonFiniteState`] message says where, when and
//! in which stage, and [`FiniteGuard::events`] keeps the same record for code that does
//! not read messages (the runner stops on it). Removing [`Frozen`] lets the island move
//! again.
//!
//! Nonsense that is still finite is caught the same way: a constrained edge more than
//! [`MAX_STRETCH`] off its rest length at a step's end (the solve keeps them within
//! 1e-9) freezes its island with a [`Quantity::Stretch`] message, and kinetic energy no
//! force in the scene explains (the [`energy`] check, at a tick's end) freezes the
//! island of its fastest particle with a [`Quantity::Speed`] message.
//!
//! Imports: [`crate::model`], [`crate::forces`] (the energy the scene's forces can
//! explain), [`crate::metrics`], [`crate::world`], [`crate::schedule`].

pub mod energy;

use bevy::ecs::system::SystemParam;
use bevy::math::DVec2;
use bevy::prelude::*;

use crate::model::NO_ISLAND;
use crate::schedule::{StepSet, StrandsStep, StrandsTick, TickSet};
use crate::world::clock::SimulationClock;
use crate::world::config::StrandsConfig;
use crate::world::particle::{Frozen, Position, SolverIndex};
use crate::world::state::ParticleState;
use crate::world::strand::StrandOf;
use crate::world::topology::Topology;

/// Which quantity went non-finite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// The force accumulated in the Forces stage.
    Force,
    /// The velocity.
    Velocity,
    /// The position.
    Position,
    /// A constrained edge's relative length error (the value's `x`), at the step's end.
    Stretch,
    /// The velocity of the most energetic particle when the scene's kinetic energy is
    /// more than anything in it explains, at a tick's end.
    Speed,
}

/// The relative length error of a constrained edge past which the guard freezes its
/// island: far above anything the solve leaves (1e-9), far below a blow-up.
pub const MAX_STRETCH: f64 = 0.01;

impl Quantity {
    /// Its name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Force => "force",
            Quantity::Velocity => "velocity",
            Quantity::Position => "position",
            Quantity::Stretch => "relative stretch",
            Quantity::Speed => "unexplained velocity",
        }
    }
}

/// A non-finite value (or an edge stretched past [`MAX_STRETCH`]) caught by the guard,
/// and what was frozen because of it.
#[derive(Message, Clone, Debug, PartialEq)]
pub struct NonFiniteState {
    /// The step it appeared in (1-based: the steps taken once this one ends).
    pub step: u64,
    /// Simulated time at the start of that step, in seconds.
    pub time: f64,
    /// The stage that produced it.
    pub stage: StepSet,
    /// The first particle (in packed order) with a non-finite value.
    pub particle: Entity,
    /// Its strand, if it belongs to one.
    pub strand: Option<Entity>,
    /// The quantity and its value.
    pub quantity: Quantity,
    /// The value.
    pub value: DVec2,
    /// How many particles had a non-finite value.
    pub bad_particles: usize,
    /// How many particles were frozen (the islands of the bad ones).
    pub frozen_particles: usize,
}

/// The guard's state: the start of the current step, what this tick froze, and every
/// event since start-up.
#[derive(Resource, Default, Debug)]
pub struct FiniteGuard {
    /// Positions at the start of the current step.
    start_position: Vec<DVec2>,
    /// Packed indices held still and where: the particles marked [`Frozen`] when the
    /// tick began, then those frozen during it. Re-applied after every stage, so a
    /// frozen particle's force (an overflowing one among them) never reaches anything.
    frozen: Vec<(u32, DVec2)>,
    /// How many of `frozen` carry the marker already.
    marked: usize,
    /// Per packed particle, whether it is in `frozen`.
    is_frozen: Vec<bool>,
    /// What the stage checks froze this step, reported at the step's end (the checks
    /// between stages read only what they scan, so a step that finds nothing pays for
    /// little more than the scans).
    found: Vec<Finding>,
    /// Every event, in order.
    pub events: Vec<NonFiniteState>,
    /// The energy check's account.
    energy: energy::EnergyAccount,
}

/// A stage check's finding, frozen at once and reported at the step's end.
#[derive(Debug)]
struct Finding {
    stage: StepSet,
    quantity: Quantity,
    first: usize,
    value: DVec2,
    bad_particles: usize,
    frozen_particles: usize,
}

/// Index of the first vector with a non-finite component. Scans in blocks whose test
/// is a branch-free reduction, so the common all-finite case runs at memory speed.
pub fn first_non_finite(values: &[DVec2]) -> Option<usize> {
    const BLOCK: usize = 256;
    values.chunks(BLOCK).enumerate().find_map(|(b, block)| {
        let bad = block
            .iter()
            .fold(false, |bad, v| bad | !v.x.is_finite() | !v.y.is_finite());
        bad.then(|| b * BLOCK + block.iter().position(|v| !v.is_finite()).unwrap_or(0))
    })
}

/// Add the guard to a step schedule's stages and the tick's write-back.
pub(crate) fn add_guard(app: &mut App) {
    app.init_resource::<FiniteGuard>()
        .add_message::<NonFiniteState>()
        .register_type::<Frozen>();
    let check = |stage: StepSet, quantity: Quantity| {
        move |guard: ResMut<FiniteGuard>, state: ResMut<ParticleState>, topology: Res<Topology>| {
            check_stage(stage, quantity, guard, state, topology)
        }
    };
    app.add_systems(
        StrandsStep,
        (
            begin_step.before(StepSet::Forces),
            check(StepSet::Forces, Quantity::Force)
                .after(StepSet::Forces)
                .before(StepSet::Predict),
            check(StepSet::Predict, Quantity::Velocity)
                .after(StepSet::Predict)
                .before(StepSet::Constrain),
            check(StepSet::Constrain, Quantity::Velocity)
                .after(StepSet::Constrain)
                .before(StepSet::Collide),
            check(StepSet::Collide, Quantity::Velocity)
                .after(StepSet::Collide)
                .before(StepSet::Integrate),
            check(StepSet::Integrate, Quantity::Position)
                .after(StepSet::Integrate)
                .before(StepSet::Measure),
            // After everything that reads the step's end: it holds what it freezes.
            check_stretch.after(StepSet::Measure),
        ),
    );
    app.add_systems(
        StrandsTick,
        (
            collect_frozen.after(TickSet::Gather).before(TickSet::Step),
            check_energy.after(TickSet::Step).before(TickSet::Writeback),
            (|mut guard: ResMut<FiniteGuard>, state: Res<ParticleState>| {
                guard.energy.end_tick(&state)
            })
            .in_set(TickSet::Writeback),
            freeze_entities.after(TickSet::Writeback),
        ),
    );
}

/// The particles already frozen, once the tick's state is gathered.
fn collect_frozen(
    mut guard: ResMut<FiniteGuard>,
    state: Res<ParticleState>,
    frozen: Query<(&SolverIndex, &Position), With<Frozen>>,
) {
    let guard = &mut *guard;
    guard.frozen.clear();
    guard.is_frozen.clear();
    guard.is_frozen.resize(state.len(), false);
    for (index, position) in &frozen {
        if let Some(i) = index.get() {
            guard.is_frozen[i] = true;
            guard.frozen.push((i as u32, position.0));
        }
    }
    guard.marked = guard.frozen.len();
    guard.energy.begin_tick(&state);
}

/// Remember where the step starts.
fn begin_step(mut guard: ResMut<FiniteGuard>, state: Res<ParticleState>) {
    guard.start_position.clear();
    guard.start_position.extend_from_slice(&state.position);
}

/// What the step's-end checks read and write to freeze and to report.
#[derive(SystemParam)]
struct CheckParams<'w, 's> {
    guard: ResMut<'w, FiniteGuard>,
    state: ResMut<'w, ParticleState>,
    topology: Res<'w, Topology>,
    clock: Res<'w, SimulationClock>,
    config: Res<'w, StrandsConfig>,
    strands: Query<'w, 's, &'static StrandOf>,
    messages: MessageWriter<'w, NonFiniteState>,
}

/// After `stage`: hold what this tick froze, then scan `quantity` and freeze the
/// islands of any non-finite particle at once (so the next stage never reads it); the
/// finding is reported at the step's end, by [`check_stretch`].
fn check_stage(
    stage: StepSet,
    quantity: Quantity,
    mut guard: ResMut<FiniteGuard>,
    mut state: ResMut<ParticleState>,
    topology: Res<Topology>,
) {
    let (guard, state) = (&mut *guard, &mut *state);
    hold_frozen(guard, state);
    let values = match quantity {
        Quantity::Force => &state.force,
        Quantity::Velocity => &state.velocity,
        Quantity::Position | Quantity::Stretch | Quantity::Speed => &state.position,
    };
    let Some(first) = first_non_finite(values) else {
        return;
    };
    let value = values[first];
    let bad: Vec<usize> = (first..values.len())
        .filter(|&i| !values[i].is_finite())
        .collect();
    let frozen_particles = freeze(guard, state, &topology, &bad);
    guard.found.push(Finding {
        stage,
        quantity,
        first,
        value,
        bad_particles: bad.len(),
        frozen_particles,
    });
}

/// Freeze the islands of the `bad` packed particles and hold them; how many particles
/// that froze.
fn freeze(
    guard: &mut FiniteGuard,
    state: &mut ParticleState,
    topology: &Topology,
    bad: &[usize],
) -> usize {
    let before = guard.frozen.len();
    freeze_islands(guard, state, topology, bad);
    hold_frozen(guard, state);
    guard.frozen.len() - before
}

impl CheckParams<'_, '_> {
    /// Freeze the islands of the `bad` packed particles, and say so: the event (the
    /// step, its stage, the `first` particle, the quantity and its value) as a
    /// message, in the guard's record and in the log.
    fn freeze_and_report(
        &mut self,
        bad: &[usize],
        (step, stage, first, quantity, value): (u64, StepSet, usize, Quantity, DVec2),
    ) {
        let frozen = freeze(&mut self.guard, &mut self.state, &self.topology, bad);
        let finding = Finding {
            stage,
            quantity,
            first,
            value,
            bad_particles: bad.len(),
            frozen_particles: frozen,
        };
        self.report(step, finding);
    }

    /// Say what `finding` froze in `step`: as a message, in the guard's record and in
    /// the log.
    fn report(&mut self, step: u64, finding: Finding) {
        let Finding {
            stage,
            quantity,
            value,
            ..
        } = finding;
        // Scanned from the same state, so the index is in range; were it not, the
        // event is still told, with no particle to name.
        let particle =
            (self.state.entity.get(finding.first).copied()).unwrap_or(Entity::PLACEHOLDER);
        let event = NonFiniteState {
            step,
            time: step.saturating_sub(1) as f64 * self.config.dt,
            stage,
            particle,
            strand: self.strands.get(particle).ok().map(|of| of.0),
            quantity,
            value,
            bad_particles: finding.bad_particles,
            frozen_particles: finding.frozen_particles,
        };
        error!(
            "bevy_strands: step {step}, {stage:?} stage: particle {particle} has {} {value}; \
             {} particles frozen",
            quantity.name(),
            event.frozen_particles
        );
        self.messages.write(event.clone());
        self.guard.events.push(event);
    }
}

/// After the Measure stage (its errors measured): report what the stage checks froze,
/// then freeze the islands of constrained edges stretched past [`MAX_STRETCH`] (nothing
/// to scan while the step's largest error is below it).
fn check_stretch(mut params: CheckParams, metrics: Res<crate::metrics::StrandMetrics>) {
    // The stage checks' findings of this step (the Integrate stage has counted it).
    let found = std::mem::take(&mut params.guard.found);
    for finding in found {
        params.report(params.clock.steps, finding);
    }
    if metrics.max_rel_length_error_now <= MAX_STRETCH {
        return;
    }
    let (guard, topology) = (&params.guard, &params.topology);
    let errors = &metrics.relative_length_error;
    let stretched = |k: usize| {
        let e = &topology.edges[k];
        let error = errors.get(k).copied().unwrap_or(0.0);
        // NaN counts: the finiteness checks have caught it already, or will.
        (e.constrained && (error > MAX_STRETCH || error.is_nan())).then_some((
            e.a as usize,
            e.b as usize,
            error,
        ))
    };
    let mut bad: Vec<usize> = Vec::new();
    let mut worst: Option<(usize, f64)> = None;
    for k in 0..topology.edges.len() {
        let Some((a, b, error)) = stretched(k) else {
            continue;
        };
        if guard.is_frozen.get(a).copied().unwrap_or(true)
            && guard.is_frozen.get(b).copied().unwrap_or(true)
        {
            continue;
        }
        bad.extend([a, b]);
        if worst.is_none_or(|(_, w)| error > w || error.is_nan()) {
            worst = Some((a, error));
        }
    }
    let Some((first, error)) = worst else {
        return;
    };
    bad.sort_unstable();
    bad.dedup();
    let event = (
        params.clock.steps,
        StepSet::Measure,
        first,
        Quantity::Stretch,
        DVec2::new(error, 0.0),
    );
    params.freeze_and_report(&bad, event);
}

/// At a tick's end: compare the scene's energy with what its forces explain, and freeze
/// the island of the most energetic particle if it has far more.
fn check_energy(
    mut params: CheckParams,
    collision: Res<crate::world::config::CollisionConfig>,
    tethers: Query<(), With<crate::world::particle::Tether>>,
) {
    let Some(first) = unexplained(&mut params, collision.thickness, !tethers.is_empty()) else {
        return;
    };
    let value = params.state.velocity[first];
    let event = (
        params.clock.steps,
        StepSet::Measure,
        first,
        Quantity::Speed,
        value,
    );
    params.freeze_and_report(&[first], event);
}

/// The most energetic counted particle when the scene's energy is more than its forces
/// explain (settling the account at the tick's end), or `None`.
fn unexplained(params: &mut CheckParams, thickness: f64, tethered: bool) -> Option<usize> {
    let (guard, state) = (&mut *params.guard, &*params.state);
    let (topology, config) = (&params.topology, &params.config);
    if state.is_empty() || guard.energy.tick_start.len() != state.len() {
        return None;
    }
    let frozen_now = guard.frozen.len() != guard.marked;
    let driven = frozen_now || energy::driven(state, tethered);
    let account = &mut guard.energy;
    if !account.accrue(state, driven) {
        return None;
    }
    let (edges, bends) = (&topology.edges[..], &topology.bends[..]);
    let changed = account.count(state, edges, bends);
    let (work, driven) = account.take_pending();
    let counted = &account.counted;
    let energy = energy::MechanicalEnergy::of(
        state,
        (edges, bends),
        config.bending,
        config.gravity,
        counted,
    );
    let free_mass: f64 = (state.mass.iter().zip(counted))
        .filter(|(_, c)| **c)
        .map(|(m, _)| m)
        .sum();
    let slack = energy::slack(free_mass, config.gravity, thickness, config.dt);
    if account.settle(energy, work, slack, changed || driven) != energy::Verdict::Unexplained {
        return None;
    }
    (0..state.len())
        .filter(|&i| account.counted[i])
        .max_by(|&i, &j| {
            let e = |k: usize| state.mass[k] * state.velocity[k].length_squared();
            e(i).total_cmp(&e(j))
        })
}

/// Freeze the islands of the `bad` packed particles at the step's start.
fn freeze_islands(
    guard: &mut FiniteGuard,
    state: &ParticleState,
    topology: &Topology,
    bad: &[usize],
) {
    let island_of = |i: usize| topology.island.get(i).copied().unwrap_or(NO_ISLAND);
    let mut islands: Vec<u32> = bad
        .iter()
        .map(|&i| island_of(i))
        .filter(|&k| k != NO_ISLAND)
        .collect();
    islands.sort_unstable();
    islands.dedup();
    let freeze = |i: usize, guard: &mut FiniteGuard| {
        if !guard.is_frozen[i] {
            guard.is_frozen[i] = true;
            guard.frozen.push((i as u32, guard.start_position[i]));
        }
    };
    for &i in bad {
        freeze(i, guard);
    }
    if !islands.is_empty() {
        for i in 0..state.len() {
            if islands.binary_search(&island_of(i)).is_ok() {
                freeze(i, guard);
            }
        }
    }
}

/// Put every particle frozen this tick back where it was frozen, at rest.
fn hold_frozen(guard: &FiniteGuard, state: &mut ParticleState) {
    for &(i, at) in &guard.frozen {
        let i = i as usize;
        state.position[i] = at;
        state.velocity[i] = DVec2::ZERO;
        state.force[i] = DVec2::ZERO;
    }
}

/// Mark the particles this tick froze, so the topology pins them from the next tick on.
fn freeze_entities(
    mut guard: ResMut<FiniteGuard>,
    state: Res<ParticleState>,
    mut commands: Commands,
) {
    for &(i, _) in &guard.frozen[guard.marked..] {
        if let Some(&entity) = state.entity.get(i as usize) {
            commands.entity(entity).insert(Frozen);
        }
    }
    guard.marked = guard.frozen.len();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_non_finite_vector_is_found_in_any_block() {
        let mut values = vec![DVec2::ONE; 1000];
        assert_eq!(first_non_finite(&values), None);
        for at in [0, 255, 256, 700, 999] {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                values[at] = DVec2::new(1.0, bad);
                assert_eq!(first_non_finite(&values), Some(at));
                values[at] = DVec2::new(bad, 1.0);
                assert_eq!(first_non_finite(&values), Some(at));
                values[at] = DVec2::ONE;
            }
        }
        values[300] = DVec2::NAN;
        values[900] = DVec2::NAN;
        assert_eq!(first_non_finite(&values), Some(300));
        assert_eq!(first_non_finite(&[]), None);
    }
}
