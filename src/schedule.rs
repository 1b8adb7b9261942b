//! The order of a step, in one place.
//!
//! A fixed tick ([`StrandsTick`]) runs the phases of [`TickSet`]: scene logic, sleeping
//! and waking, the topology rebuild, gathering entity state into the packed arrays, `substeps` runs of
//! the step schedule, and the write-back. A step that would end in the collision
//! fail-safe is put back (`halving`) and taken as two steps of half its size,
//! down to `dt / 2^max_step_halvings` ([`StrandsConfig::max_step_halvings`]). A step
//! ([`StrandsStep`]) runs the stages of [`StepSet`] in order:
//!
//! 1. **Forces** — external forces, gravity, damping, springs, bending, tethers.
//! 2. **Predict** — symplectic Euler predictor `v* = v + dt f / m`.
//! 3. **Constrain** — the sub-stages of [`ConstrainSet`], in order:
//!    1. **Project** — every island's velocities projected so that each constrained
//!       edge ends the step at its rest length.
//!    2. **Speculate** — the contact solve: every point that motion would bring
//!       within reach of an edge becomes a contact row (keep a thickness apart, with
//!       friction), and every island the rows touch is projected again together with
//!       them, both sides of each contact moving, every edge exact.
//! 4. **Collide** — the sub-stages of [`CollideSet`], in order:
//!    1. **Proximity** — the contact solve's contacts become the step's; without a
//!       contact solve (the relaxation baselines, or speculation off), pairs that
//!       would end the step closer than the thickness are pushed apart by impulses.
//!    2. **Impulses** — continuous point–edge detection, an impulse per collision,
//!       repeated until a pass finds none; the rigid-impact-zone fail-safe if the cap
//!       is reached.
//!    3. **Contact loop** — the islands contacts touched are projected onto their
//!       constraints again with every contact as an inequality row, then the
//!       Impulses sub-stage's detection runs again; repeated until a pass applies no
//!       impulse. Collisions always come last, so non-penetration is never traded for
//!       length.
//!    4. **Account** — the step's collision figures.
//! 5. **Integrate** — `x += dt v`.
//! 6. **Measure** — length errors, crossings, counts.
//!
//! Between stages the finiteness guard (the crate's `guard` module) scans what each
//! stage wrote. Each area's plugin adds its systems to these sets; this module fixes
//! their order and runs the steps.
//!
//! Driven by a schedule (`FixedPostUpdate` by default), a tick runs inside
//! [`StrandsSystems`] each time that schedule runs and covers the schedule's delta: the
//! step is `delta / substeps`. The app's clocks are left alone. Tests drive the
//! simulation with `world.run_schedule(StrandsTick)`: no wall clock.

use bevy::ecs::schedule::{InternedScheduleLabel, LogLevel, ScheduleBuildSettings, ScheduleLabel};
use bevy::prelude::*;

use crate::world::clock::StepTiming;
use crate::world::config::StrandsConfig;

/// One fixed tick: prepare, gather, `substeps` steps, write back.
#[derive(ScheduleLabel, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StrandsTick;

/// One step of size `dt`.
#[derive(ScheduleLabel, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StrandsStep;

/// The phases of a tick, in order.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TickSet {
    /// Scene logic that spawns, despawns or drives particles (factories, tools); not
    /// run by a tick that only synchronises.
    Prepare,
    /// Wake sleeping strands that something will reach or that were written to, and put
    /// to sleep the groups that have rested long enough (the `sleeping` module).
    Sleep,
    /// Rebuild the topology and derived caches if anything structural changed.
    Topology,
    /// Copy entity state into the packed arrays.
    Gather,
    /// Run the steps.
    Step,
    /// Copy the packed state back to the entities.
    Writeback,
}

/// The stages of a step, in order.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StepSet {
    /// Accumulate forces.
    Forces,
    /// Symplectic Euler predictor velocities.
    Predict,
    /// Inextensibility: filter the velocities so every constrained edge keeps its length.
    Constrain,
    /// Collision processing: the sub-stages of [`CollideSet`].
    Collide,
    /// Advance positions.
    Integrate,
    /// Update the metrics.
    Measure,
}

/// The sub-stages of [`StepSet::Constrain`], in order.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ConstrainSet {
    /// Every island projected onto its edge constraints.
    Project,
    /// The contact solve: speculative contact rows for the points the projected
    /// motion brings close to an edge, and the islands they touch projected again
    /// together with them.
    Speculate,
}

/// The sub-stages of [`StepSet::Collide`], in order.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CollideSet {
    /// Candidate pairs from the broad phase; proximity impulses keep pairs a thickness
    /// apart.
    Proximity,
    /// Continuous detection with impulses until a pass is clean, then the fail-safe.
    Impulses,
    /// Re-projection of the islands in contact with contact rows, alternating with
    /// detection and impulses until nothing changes.
    ContactLoop,
    /// The step's collision counts.
    Account,
}

/// The system set, in the driving schedule, that runs a tick: order your own systems
/// `.before(StrandsSystems)` (to push on strands) or `.after(StrandsSystems)` (to read
/// where they went).
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StrandsSystems;

/// Sets up the two schedules and the order of their sets, and runs the steps.
pub struct SchedulePlugin {
    /// The schedule that runs a tick each time it runs; `None` to drive by hand.
    pub driver: Option<InternedScheduleLabel>,
}

impl Plugin for SchedulePlugin {
    fn build(&self, app: &mut App) {
        let mut step = Schedule::new(StrandsStep);
        step.set_build_settings(ScheduleBuildSettings {
            ambiguity_detection: LogLevel::Error,
            ..default()
        });
        step.set_executor(bevy::ecs::schedule::SingleThreadedExecutor::new());
        app.add_schedule(step);
        // A tick's phases run one after another and the heavy work inside them is
        // spread over the plugin's own threads: a multi-threaded executor would only add
        // its wake-ups (a tenth of a millisecond a tick, most of a small scene's time).
        let mut tick = Schedule::new(StrandsTick);
        tick.set_executor(bevy::ecs::schedule::SingleThreadedExecutor::new());
        app.add_schedule(tick);
        app.init_resource::<StepTiming>();

        app.configure_sets(
            StrandsTick,
            (
                TickSet::Prepare,
                TickSet::Sleep,
                TickSet::Topology,
                TickSet::Gather,
                TickSet::Step,
                TickSet::Writeback,
            )
                .chain(),
        );
        // Scene logic follows simulated time: a paused tick does not run it.
        app.configure_sets(
            StrandsTick,
            (TickSet::Prepare, TickSet::Sleep).run_if(stepping),
        );
        app.configure_sets(
            StrandsStep,
            (
                StepSet::Forces,
                StepSet::Predict,
                StepSet::Constrain,
                StepSet::Collide,
                StepSet::Integrate,
                StepSet::Measure,
            )
                .chain(),
        );
        app.configure_sets(
            StrandsStep,
            (ConstrainSet::Project, ConstrainSet::Speculate)
                .chain()
                .in_set(StepSet::Constrain),
        );
        app.configure_sets(
            StrandsStep,
            (
                CollideSet::Proximity,
                CollideSet::Impulses,
                CollideSet::ContactLoop,
                CollideSet::Account,
            )
                .chain()
                .in_set(StepSet::Collide),
        );

        if let Some(driver) = self.driver {
            app.add_systems(driver, drive_tick.in_set(StrandsSystems));
        }
    }
}

/// While set, a tick only synchronises (topology, gather, write-back) and takes no step:
/// what a paused simulation runs, so that edits made while paused show at once.
#[derive(Resource, Default, Clone, Copy, Debug)]
pub struct SyncOnly(pub(crate) bool);

/// Run condition: this tick takes steps (it is not a paused tick that only
/// synchronises).
pub fn stepping(sync: Option<Res<SyncOnly>>) -> bool {
    !sync.is_some_and(|s| s.0)
}

/// Run one tick covering the driving schedule's delta (the driver schedule's system);
/// paused, or with no time elapsed, one that takes no step.
fn drive_tick(world: &mut World) {
    let delta = world.resource::<Time>().delta_secs_f64();
    let mut config = world.resource_mut::<StrandsConfig>();
    let dt = delta / config.substeps.max(1) as f64;
    let stepping = !config.paused && dt.is_finite() && dt > 0.0;
    // Written only when it changes, so a fixed schedule does not mark the config
    // changed every tick.
    if stepping && config.dt != dt {
        config.dt = dt;
    }
    world.insert_resource(SyncOnly(!stepping));
    world.run_schedule(StrandsTick);
    world.insert_resource(SyncOnly(false));
}

/// Run a tick that only synchronises: the topology rebuilt and the packed state
/// gathered from the entities, as at the end of a tick, without a step and without the
/// scene logic of [`TickSet::Prepare`]. Does nothing in a world without the schedule.
pub fn synchronise(world: &mut World) {
    world.insert_resource(SyncOnly(true));
    // Err only when the schedule does not exist: then there is nothing to synchronise.
    let _ = world.try_run_schedule(StrandsTick);
    world.insert_resource(SyncOnly(false));
}
