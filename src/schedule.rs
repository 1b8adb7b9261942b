//! The order of a step, in one place.
//!
//! A fixed tick ([`StrandsTick`]) prepares the topology, gathers entity state into the
//! packed arrays, runs `substeps` steps of [`StrandsStep`], and writes the state back.
//! A step runs the stages of [`StepSet`] in order:
//!
//! 1. **Forces** — external forces, gravity, damping, springs, bending.
//! 2. **Predict** — symplectic Euler predictor `v* = v + dt f / m`.
//! 3. **Constrain** — impulses so every constrained edge ends the step at rest length.
//! 4. **Collide** — continuous point–edge collision impulses, then the fail-safe.
//! 5. **Integrate** — `x += dt v`.
//! 6. **Measure** — length errors, crossings, counts.
//!
//! Tests drive the simulation with `world.run_schedule(StrandsTick)`: no wall clock.

use bevy::ecs::schedule::{InternedScheduleLabel, LogLevel, ScheduleBuildSettings, ScheduleLabel};
use bevy::platform::time::Instant;
use bevy::prelude::*;
use bevy::time::Fixed;

use crate::config::StrandsConfig;
use crate::forces::accumulate_forces;
use crate::forces::tether::apply_tethers;
use crate::integrate::{integrate, predict};
use crate::metrics::{StrandMetrics, count_elements, measure, record_length_error_history};
use crate::state::{gather, write_back};
use crate::topology::{detect_strand_edits, rebuild_topology, topology_dirty};

/// One fixed tick: prepare, gather, `substeps` steps, write back.
#[derive(ScheduleLabel, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StrandsTick;

/// One step of size `dt`.
#[derive(ScheduleLabel, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StrandsStep;

/// The phases of a tick, in order.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TickSet {
    /// Scene logic that spawns, despawns or drives particles (factories, tools).
    Prepare,
    /// Rebuild the topology and derived caches if anything structural changed.
    Topology,
    /// Copy entity state into the packed arrays.
    Gather,
    /// Run the steps.
    Step,
    /// Copy the packed state back to the entities.
    Writeback,
}

/// The stages of a step, in order (DESIGN §4).
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StepSet {
    /// Accumulate forces.
    Forces,
    /// Symplectic Euler predictor velocities.
    Predict,
    /// Inextensibility: filter the velocities so every constrained edge keeps its length.
    Constrain,
    /// Continuous collision impulses and the fail-safe.
    Collide,
    /// Advance positions.
    Integrate,
    /// Update the metrics.
    Measure,
}

/// Simulated time and steps taken.
#[derive(Resource, Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[reflect(Resource)]
pub struct SimulationClock {
    /// Simulated seconds since start.
    pub time: f64,
    /// Steps taken since start.
    pub steps: u64,
}

impl SimulationClock {
    /// Account for one step of `dt`.
    pub fn advance(&mut self, dt: f64) {
        self.steps += 1;
        // Multiply rather than accumulate so long runs do not drift.
        self.time = self.steps as f64 * dt;
    }
}

/// Sets up the two schedules, their stages and the core systems.
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
        app.init_schedule(StrandsTick);

        app.configure_sets(
            StrandsTick,
            (
                TickSet::Prepare,
                TickSet::Topology,
                TickSet::Gather,
                TickSet::Step,
                TickSet::Writeback,
            )
                .chain(),
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
        app.add_systems(
            StrandsTick,
            (
                (detect_strand_edits, rebuild_topology.run_if(topology_dirty))
                    .chain()
                    .in_set(TickSet::Topology),
                count_elements
                    .in_set(TickSet::Topology)
                    .after(rebuild_topology),
                gather.in_set(TickSet::Gather),
                run_steps.in_set(TickSet::Step),
                (write_back, record_length_error_history).in_set(TickSet::Writeback),
            ),
        );
        app.add_systems(
            StrandsStep,
            (
                (accumulate_forces, apply_tethers)
                    .chain()
                    .in_set(StepSet::Forces),
                predict.in_set(StepSet::Predict),
                integrate.in_set(StepSet::Integrate),
                measure.in_set(StepSet::Measure),
            ),
        );

        if let Some(driver) = self.driver {
            app.add_systems(driver, drive_tick);
            app.add_systems(PreUpdate, sync_fixed_timestep);
        }
    }
}

/// While set, a tick only synchronises (topology, gather, write-back) and takes no step:
/// what a paused simulation runs, so that edits made while paused show at once.
#[derive(Resource, Default, Clone, Copy, Debug)]
struct SyncOnly(bool);

/// Run `substeps` steps and account their wall time.
fn run_steps(world: &mut World) {
    if world.get_resource::<SyncOnly>().is_some_and(|s| s.0) {
        return;
    }
    let substeps = world.resource::<StrandsConfig>().substeps;
    {
        let mut metrics = world.resource_mut::<StrandMetrics>();
        metrics.tick_max_rel_length_error = 0.0;
        metrics.tick_max_rel_length_error_free = 0.0;
    }
    let start = Instant::now();
    world.schedule_scope(StrandsStep, |world, schedule| {
        for _ in 0..substeps {
            schedule.run(world);
        }
    });
    let seconds = start.elapsed().as_secs_f64();
    let mut metrics = world.resource_mut::<StrandMetrics>();
    metrics.wall_seconds += seconds;
    metrics.last_tick_seconds = seconds;
}

/// Run one tick (the driver schedule's system); paused, one that takes no step.
fn drive_tick(world: &mut World) {
    let paused = world.resource::<StrandsConfig>().paused;
    world.insert_resource(SyncOnly(paused));
    world.run_schedule(StrandsTick);
    world.insert_resource(SyncOnly(false));
}

/// Keep the fixed timestep equal to the simulated time of one tick.
fn sync_fixed_timestep(config: Res<StrandsConfig>, fixed: Option<ResMut<Time<Fixed>>>) {
    if let Some(mut fixed) = fixed
        && config.is_changed()
    {
        let seconds = config.tick_seconds();
        if seconds.is_finite() && seconds > 0.0 {
            fixed.set_timestep_seconds(seconds);
        }
    }
}
