//! Step halving, the step's own fallback: what a step changes, saved before it so that a step that would
//! end in the collision fail-safe can be put back and taken as two halves.
//!
//! Each area registers the state its step systems carry from one step to the next (the
//! packed particles, the metrics, the clock, the contact warm starts, a body
//! coupling's impulses), with how to copy it into a buffer kept from step to step and
//! back: a steady-state step saves without allocating. Buffers rebuilt every step are
//! not saved.

use std::marker::PhantomData;

use bevy::ecs::component::Mutable;
use bevy::platform::time::Instant;
use bevy::prelude::*;

use crate::metrics::StrandMetrics;
use crate::schedule::{StrandsStep, StrandsTick, SyncOnly, TickSet};
use crate::split_ahead::{SplitAhead, StepWork};
use crate::world::clock::{SimulationClock, StepTiming};
use crate::world::config::StrandsConfig;
use crate::world::state::ParticleState;

/// Runs a tick's steps, each taken again in halves where it would end in the
/// fail-safe, and registers what every step carries forward.
pub struct HalvingPlugin;

impl Plugin for HalvingPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<StepSplit>()
            .add_systems(StrandsTick, run_steps.in_set(TickSet::Step));
        // What every step carries forward, for a step taken again in halves.
        app.save_for_halving::<ParticleState, ParticleState>(
            |state, saved| saved.copy_step_from(state),
            |state, saved| {
                debug_assert_eq!(state.len(), saved.position.len(), "resized within a step");
                state.copy_step_from(saved)
            },
        )
        .save_for_halving::<StrandMetrics, StrandMetrics>(
            |metrics, saved| saved.copy_from(metrics),
            |metrics, saved| metrics.copy_from(saved),
        )
        .save_clone_for_halving::<SimulationClock>();
    }
}

/// Run `substeps` steps and account their wall time.
fn run_steps(world: &mut World) {
    if world.get_resource::<SyncOnly>().is_some_and(|s| s.0) {
        return;
    }
    let config = world.resource::<StrandsConfig>();
    let (substeps, halvings) = (config.substeps, config.max_step_halvings);
    let max_level = config.max_split_ahead.min(halvings);
    let start = Instant::now();
    world.schedule_scope(StrandsStep, |world, schedule| {
        for _ in 0..substeps {
            let level = if may_take_again(world, halvings) {
                world.resource::<StepSplit>().0.level.min(max_level)
            } else {
                0
            };
            let before = StepWork::of(world.resource::<StrandMetrics>());
            step(world, schedule, halvings, level);
            let mut metrics = world.resource_mut::<StrandMetrics>();
            metrics.split_steps += u64::from(level > 0);
            let hard = StepWork::of(&metrics).hard_since(&before);
            world
                .resource_mut::<StepSplit>()
                .0
                .after_step(hard, max_level);
        }
    });
    let seconds = start.elapsed().as_secs_f64();
    let mut timing = world.resource_mut::<StepTiming>();
    timing.wall_seconds += seconds;
    timing.last_tick_seconds = seconds;
}

/// Whether a step may be taken again in halves, or in parts ahead: what forbids the
/// first (an avian body's pose moved between ticks, which a shorter step corrects
/// faster) forbids the second.
fn may_take_again(world: &World, halvings: u32) -> bool {
    halvings > 0 && (world.get_resource::<HalvingSaves>()).is_some_and(|saves| saves.allows(world))
}

/// How the world's next steps are split ahead (see `split_ahead`).
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct StepSplit(pub SplitAhead);

/// Run one step, as `2^split` parts from the start where `split` and `halvings` allow;
/// if it (or a part) ends in the collision fail-safe and `halvings` allow, put back
/// what it changed and take it as two steps of half the size instead (each of which
/// may be halved again). Whether it ended in the fail-safe after all; such a step
/// counts once in [`StrandMetrics::failsafe_steps`] however it was cut.
fn step(world: &mut World, schedule: &mut Schedule, halvings: u32, split: u32) -> bool {
    if split > 0 && halvings > 0 {
        let failsafe = world.resource::<StrandMetrics>().failsafe_steps;
        return halves(world, schedule, halvings, split - 1, failsafe);
    }
    let saving = may_take_again(world, halvings);
    if saving {
        with_saves(world, |saves, world| saves.save(world));
    }
    let failsafe = world.resource::<StrandMetrics>().failsafe_steps;
    schedule.run(world);
    let failed = world.resource::<StrandMetrics>().failsafe_steps != failsafe;
    if !saving || !failed {
        return failed;
    }
    // (A halved step's own save replaces this one: it is no longer needed.)
    with_saves(world, |saves, world| saves.restore(world));
    world.resource_mut::<StrandMetrics>().halved_steps += 1;
    halves(world, schedule, halvings, 0, failsafe)
}

/// Run `f` on the saves with the world at hand. The saves' lists are taken out and put
/// back rather than the resource itself (`resource_scope`), which would move it out of
/// its storage and back every step: a third of what saving cost a small scene.
fn with_saves(world: &mut World, f: impl FnOnce(&mut HalvingSaves, &mut World)) {
    let mut saves = std::mem::take(&mut *world.resource_mut::<HalvingSaves>());
    f(&mut saves, world);
    *world.resource_mut::<HalvingSaves>() = saves;
}

/// Take the step as two halves, each split `split` more times ahead; `failsafe` is
/// the count of fail-safe steps before it.
fn halves(
    world: &mut World,
    schedule: &mut Schedule,
    halvings: u32,
    split: u32,
    failsafe: u64,
) -> bool {
    let dt = world.resource::<StrandsConfig>().dt;
    world.resource_mut::<StrandsConfig>().dt = 0.5 * dt;
    // The clock's time is its steps times the step: counted in halves meanwhile, so
    // that each half ends at its own time, and as one step of `dt` after.
    let steps = world.resource::<SimulationClock>().steps;
    world.resource_mut::<SimulationClock>().steps = 2 * steps;
    let first = step(world, schedule, halvings - 1, split);
    // Where halving the first half all the way did not spare it the fail-safe, halving
    // is not what this motion needs: the second half is taken whole.
    let second = step(world, schedule, if first { 0 } else { halvings - 1 }, split);
    world.resource_mut::<StrandsConfig>().dt = dt;
    let mut clock = world.resource_mut::<SimulationClock>();
    clock.steps = steps + 1;
    clock.time = clock.steps as f64 * dt;
    let failed = first || second;
    world.resource_mut::<StrandMetrics>().failsafe_steps = failsafe + u64::from(failed);
    failed
}

/// One registered resource: its saved copy and how to make and restore it.
trait Entry: Send + Sync {
    fn save(&mut self, world: &World);
    fn restore(&self, world: &mut World);
}

struct Slot<T, S> {
    saved: S,
    present: bool,
    save: fn(&T, &mut S),
    restore: fn(&mut T, &S),
    resource: PhantomData<fn() -> T>,
}

impl<T: Resource<Mutability = Mutable>, S: Send + Sync + 'static> Entry for Slot<T, S> {
    fn save(&mut self, world: &World) {
        self.present = world
            .get_resource::<T>()
            .map(|r| (self.save)(r, &mut self.saved))
            .is_some();
    }

    fn restore(&self, world: &mut World) {
        if let (true, Some(mut resource)) = (self.present, world.get_resource_mut::<T>()) {
            (self.restore)(&mut resource, &self.saved);
        }
    }
}

/// The state a step carries forward, as registered by each area's plugin, and its copy
/// from before the current step.
#[derive(Resource, Default)]
pub struct HalvingSaves {
    entries: Vec<Box<dyn Entry>>,
    vetoes: Vec<fn(&World) -> bool>,
}

impl std::fmt::Debug for HalvingSaves {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HalvingSaves")
            .field("registered", &self.entries.len())
            .field("vetoes", &self.vetoes.len())
            .finish()
    }
}

impl HalvingSaves {
    /// Save resource `T` before each step with `save` (into a buffer of type `S` kept
    /// between steps), put back by `restore` when the step is taken again.
    pub fn register<T: Resource<Mutability = Mutable>, S: Default + Send + Sync + 'static>(
        &mut self,
        save: fn(&T, &mut S),
        restore: fn(&mut T, &S),
    ) {
        self.entries.push(Box::new(Slot {
            saved: S::default(),
            present: false,
            save,
            restore,
            resource: PhantomData,
        }));
    }

    /// Save the whole of resource `T` by `clone_from` (which, for a type whose
    /// `clone_from` reuses its buffers, allocates nothing in a steady state).
    pub fn register_clone<T: Resource<Mutability = Mutable> + Clone + Default>(&mut self) {
        self.register::<T, T>(
            |r, saved| saved.clone_from(r),
            |r, saved| r.clone_from(saved),
        );
    }

    /// Never take a step again while `veto` says so (state a step cannot put back).
    pub fn forbid_when(&mut self, veto: fn(&World) -> bool) {
        self.vetoes.push(veto);
    }

    /// Whether a step of `world` may be taken again.
    pub fn allows(&self, world: &World) -> bool {
        !self.vetoes.iter().any(|veto| veto(world))
    }

    /// Save every registered resource of `world`, replacing the last save.
    pub fn save(&mut self, world: &World) {
        for entry in &mut self.entries {
            entry.save(world);
        }
    }

    /// Put every resource saved by the last [`HalvingSaves::save`] back as it was.
    pub fn restore(&self, world: &mut World) {
        for entry in &self.entries {
            entry.restore(world);
        }
    }
}

/// Registering state with [`HalvingSaves`] from a plugin.
pub trait HalvingApp {
    /// See [`HalvingSaves::register`].
    fn save_for_halving<T: Resource<Mutability = Mutable>, S: Default + Send + Sync + 'static>(
        &mut self,
        save: fn(&T, &mut S),
        restore: fn(&mut T, &S),
    ) -> &mut Self;
    /// See [`HalvingSaves::register_clone`].
    fn save_clone_for_halving<T: Resource<Mutability = Mutable> + Clone + Default>(
        &mut self,
    ) -> &mut Self;
}

impl HalvingApp for App {
    fn save_for_halving<T: Resource<Mutability = Mutable>, S: Default + Send + Sync + 'static>(
        &mut self,
        save: fn(&T, &mut S),
        restore: fn(&mut T, &S),
    ) -> &mut Self {
        self.init_resource::<HalvingSaves>();
        self.world_mut()
            .resource_mut::<HalvingSaves>()
            .register(save, restore);
        self
    }

    fn save_clone_for_halving<T: Resource<Mutability = Mutable> + Clone + Default>(
        &mut self,
    ) -> &mut Self {
        self.init_resource::<HalvingSaves>();
        self.world_mut()
            .resource_mut::<HalvingSaves>()
            .register_clone::<T>();
        self
    }
}
