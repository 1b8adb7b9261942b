//! The headless runner: a scenario in, a report out, no window and no wall clock in
//! the loop. The `strands` binary is a thin command line over [`run`].

use std::path::PathBuf;

use bevy::platform::time::Instant;
use bevy::prelude::*;
use thiserror::Error;

use bevy_strands::constraints::Islands;
use bevy_strands::constraints::islands::IslandKind;
use bevy_strands::constraints::projection::ConstraintDirection;
use bevy_strands::metrics::LengthErrorHistory;
use bevy_strands::prelude::*;

use crate::builtin::{builtin, builtin_names};
use crate::energy::EnergyLedger;
use crate::export::plot::plot_length_error;
use crate::export::{ExportError, FrameSettings, Recorder};
use crate::free::FreeSpeeds;
use crate::profile::{StageProfile, add_stage_markers};
use crate::report::{CrossingReport, IslandReport, Report};
use crate::scenario::{Scenario, ScenarioError};
use crate::scenes::ScenesPlugin;
use crate::scenes::drain::Drain;
use crate::scenes::spaghetti_factory::SpaghettiFactory;
use crate::snapshot::{RunSnapshot, RunSnapshotError};
use crate::spawn::spawn_scenario;
use bevy_strands::snapshot::SnapshotError;

/// What to run, and the command line's overrides of the scene.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Built-in scenario name (ignored when `scene_file` is given, except in errors).
    pub scenario: String,
    /// A scene file to run instead of the built-in one.
    pub scene_file: Option<PathBuf>,
    /// Simulated seconds, instead of the scene's duration.
    pub seconds: Option<f64>,
    /// Step size, instead of the scene's.
    pub dt: Option<f64>,
    /// Steps per tick, instead of the scene's.
    pub substeps: Option<u32>,
    /// Threads a stage may use (0 or `None`: one per core); the report is the same
    /// whatever the count.
    pub threads: Option<usize>,
    /// Constraint solver, instead of the scene's.
    pub solver: Option<String>,
    /// Bending model, instead of the scene's.
    pub bending: Option<String>,
    /// Contact solver, instead of the scene's.
    pub contact_solver: Option<String>,
    /// Projection iteration cap, instead of the scene's.
    pub iterations: Option<u32>,
    /// Halvings of a step that would end in the fail-safe, instead of the scene's.
    pub step_halvings: Option<u32>,
    /// Levels a hard step's successors are split ahead, instead of the scene's.
    pub split_ahead: Option<u32>,
    /// Keep stretch springs on constrained edges.
    pub stretch_springs: bool,
    /// Never put strands to sleep.
    pub no_sleep: bool,
    /// Take the constraint direction at the start of the step.
    pub start_of_step: bool,
    /// Whether to count edge crossings at every step end.
    pub check_crossings: bool,
    /// Turn collisions off.
    pub no_collisions: bool,
    /// Strands of the scale scenario, instead of the scene's.
    pub strands: Option<usize>,
    /// Particles per strand of the scale scenario, instead of the scene's.
    pub particles: Option<usize>,
    /// Write an animated GIF here.
    pub gif: Option<PathBuf>,
    /// Write numbered PNG frames into this directory.
    pub frames: Option<PathBuf>,
    /// Write the length-error plot (PNG) here.
    pub plot: Option<PathBuf>,
    /// Frame size and rate of `gif` and `frames`.
    pub frame_settings: FrameSettings,
    /// Write a snapshot at the end of the first tick at or after this simulated time...
    pub snapshot_at: Option<f64>,
    /// ...to this file.
    pub snapshot: Option<PathBuf>,
    /// Continue the run saved in this snapshot instead of starting the scenario.
    pub from: Option<PathBuf>,
    /// End the run at the first step that ends with crossed edges.
    pub stop_on_crossing: bool,
    /// Time each stage of the tick and the step (`StageProfile`), for the report.
    pub profile: bool,
}

/// Why a run could not start or finish.
#[derive(Debug, Error)]
pub enum RunError {
    /// Pictures could not be written.
    #[error(transparent)]
    Export(#[from] ExportError),
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// A snapshot could not be written or read.
    #[error(transparent)]
    Snapshot(#[from] RunSnapshotError),
    /// A snapshot could not be restored.
    #[error("{path}: {source}")]
    Restore {
        /// The snapshot file.
        path: String,
        /// What is wrong.
        source: SnapshotError,
    },
    /// The state went non-finite: the run stops there rather than report it.
    #[error(
        "the state went non-finite in step {step} (t = {time} s), {stage} stage: {what}; \
         the run stops (is a step, a force or a velocity far too large for the scene?)"
    )]
    NonFinite {
        /// The step that made it (1-based: the steps taken once it ends).
        step: u64,
        /// Simulated time at the start of that step, in seconds.
        time: String,
        /// The stage of the step that made it.
        stage: String,
        /// The particle and the value.
        what: String,
    },
    /// No built-in scenario has that name.
    #[error("unknown scenario '{name}'; valid scenarios: {valid}")]
    UnknownScenario {
        /// The name given.
        name: String,
        /// The valid names.
        valid: String,
    },
}

/// The scenario the options describe, overrides applied and validated.
pub fn load_scenario(options: &RunOptions) -> Result<Scenario, RunError> {
    let scenario = match &options.scene_file {
        Some(path) => Scenario::load(path)?,
        None => builtin(&options.scenario)
            .ok_or_else(|| RunError::UnknownScenario {
                name: options.scenario.clone(),
                valid: builtin_names().join(", "),
            })?
            .scenario()?,
    };
    apply_overrides(scenario, options)
}

/// The command line's overrides applied to `scenario`, validated.
fn apply_overrides(mut scenario: Scenario, options: &RunOptions) -> Result<Scenario, RunError> {
    let command_line = |item: &str, problem: String| {
        RunError::Scenario(ScenarioError::new("command line", item, problem))
    };
    if let Some(seconds) = options.seconds {
        scenario.duration = seconds;
    }
    if let Some(dt) = options.dt {
        scenario.step.dt = dt;
    }
    if let Some(substeps) = options.substeps {
        scenario.step.substeps = substeps;
    }
    if let Some(threads) = options.threads {
        scenario.step.threads = threads;
    }
    if let Some(solver) = &options.solver {
        scenario.constraints.solver = solver.parse().map_err(|e| command_line("--solver", e))?;
    }
    if let Some(bending) = &options.bending {
        scenario.step.bending = bending.parse().map_err(|e| command_line("--bending", e))?;
    }
    if let Some(solver) = &options.contact_solver {
        scenario.contact.solver = solver
            .parse()
            .map_err(|e| command_line("--contact-solver", e))?;
    }
    if let Some(iterations) = options.iterations {
        scenario.constraints.max_iterations = iterations;
    }
    if let Some(halvings) = options.step_halvings {
        scenario.step.max_step_halvings = halvings;
    }
    if let Some(levels) = options.split_ahead {
        scenario.step.max_split_ahead = levels;
    }
    scenario.constraints.stretch_springs |= options.stretch_springs;
    if options.no_sleep {
        scenario.step.sleep.enabled = false;
    }
    if options.start_of_step {
        scenario.constraints.direction = ConstraintDirection::StartOfStep;
    }
    if options.no_collisions {
        scenario.collisions.enabled = false;
    }
    scenario.collisions.check_crossings = options.check_crossings;
    if options.strands.is_some() || options.particles.is_some() {
        let Some(scale) = &mut scenario.scale else {
            return Err(command_line(
                "--strands/--particles",
                format!(
                    "only the scale scenario has them; {} has no scale section",
                    scenario.name
                ),
            ));
        };
        scale.strands = options.strands.unwrap_or(scale.strands);
        scale.particles = options.particles.unwrap_or(scale.particles);
    }
    if let Some(at) = options.snapshot_at
        && !(at.is_finite() && at >= 0.0)
    {
        return Err(command_line(
            "--snapshot-at",
            format!("{at} must be a simulated time, zero or positive"),
        ));
    }
    if options.snapshot_at.is_some() != options.snapshot.is_some() {
        return Err(command_line(
            "--snapshot-at/--snapshot",
            "give both: the time and the file".into(),
        ));
    }
    scenario.validate("command line")?;
    Ok(scenario)
}

/// An app with the simulation driven by hand, the scenario logic, and the scenario
/// spawned.
pub fn headless_app(scenario: &Scenario) -> Result<App, RunError> {
    let mut app = App::new();
    app.add_plugins((StrandsPlugin::manual(), ScenesPlugin));
    app.finish();
    app.cleanup();
    spawn_scenario(app.world_mut(), scenario)?;
    Ok(app)
}

/// An app with the simulation driven by hand and the run saved in `snapshot` restored.
pub fn restored_app(snapshot: &RunSnapshot, path: &str) -> Result<App, RunError> {
    let mut app = App::new();
    app.add_plugins((StrandsPlugin::manual(), ScenesPlugin));
    app.finish();
    app.cleanup();
    snapshot
        .restore(app.world_mut())
        .map_err(|source| RunError::Restore {
            path: path.to_string(),
            source,
        })?;
    Ok(app)
}

/// Run the scenario until its duration (from its start, or from a snapshot) and report.
/// `progress` is told the fraction done after every tick.
pub fn run(options: &RunOptions, mut progress: impl FnMut(f64)) -> Result<Report, RunError> {
    let (scene, mut app) = match &options.from {
        Some(path) => {
            let mut snapshot = RunSnapshot::load(path)?;
            snapshot.scenario = apply_overrides(snapshot.scenario, options)?;
            let app = restored_app(&snapshot, &path.display().to_string())?;
            (snapshot.scenario, app)
        }
        None => {
            let scene = load_scenario(options)?;
            let app = headless_app(&scene)?;
            (scene, app)
        }
    };
    if options.profile {
        add_stage_markers(&mut app);
    }
    let world = app.world_mut();
    if options.check_crossings {
        let mut metrics = world.resource_mut::<StrandMetrics>();
        metrics.edge_crossings.get_or_insert(0);
    }
    let mut notes = Vec::new();
    if let Some(path) = &options.from {
        let clock = world.resource::<SimulationClock>();
        notes.push(format!(
            "continued from {} at step {} (t = {:.4} s)",
            path.display(),
            clock.steps,
            clock.time
        ));
    }
    let mut snapshot_due = options.snapshot_at.zip(options.snapshot.clone());
    let start_time = world.resource::<SimulationClock>().time;
    if options.plot.is_some() {
        world.init_resource::<LengthErrorHistory>();
    }
    let mut recorder = if options.gif.is_some() || options.frames.is_some() {
        Some(Recorder::new(
            options.frame_settings,
            scene.view(),
            &scene.name,
            options.gif.as_deref(),
            options.frames.as_deref(),
        )?)
    } else {
        None
    };

    let total_steps = (scene.duration / scene.step.dt).round().max(1.0) as u64;
    let mut particle_steps = 0u64;
    // The ticks alone: drawing and writing pictures is not the simulation's cost.
    let mut wall_seconds = 0.0;
    let mut ledger = EnergyLedger::default();
    loop {
        let steps = world.resource::<SimulationClock>().steps;
        if steps >= total_steps {
            break;
        }
        let substeps = (total_steps - steps).min(scene.step.substeps as u64) as u32;
        world.resource_mut::<StrandsConfig>().substeps = substeps;
        let tick_start = Instant::now();
        world.run_schedule(StrandsTick);
        wall_seconds += tick_start.elapsed().as_secs_f64();
        if let Some(event) = world.resource::<FiniteGuard>().events.first() {
            return Err(non_finite_error(world, event));
        }
        ledger.observe(world);
        particle_steps += world.resource::<ParticleState>().len() as u64 * substeps as u64;
        progress(world.resource::<SimulationClock>().steps as f64 / total_steps as f64);
        if let Some(recorder) = &mut recorder {
            recorder.capture_if_due(world)?;
        }
        let clock = *world.resource::<SimulationClock>();
        if let Some((at, path)) = &snapshot_due
            && clock.time + 1e-9 * scene.step.dt >= *at
        {
            RunSnapshot::capture(world, &scene).save(path)?;
            notes.push(format!(
                "snapshot written to {} at step {} (t = {:.4} s)",
                path.display(),
                clock.steps,
                clock.time
            ));
            snapshot_due = None;
        }
        if options.stop_on_crossing && world.resource::<StrandMetrics>().first_crossing.is_some() {
            notes.push(format!(
                "stopped at the first crossing (step {}, t = {:.4} s)",
                clock.steps, clock.time
            ));
            break;
        }
    }
    let (blocked, withdrawn) = world
        .query::<&SpaghettiFactory>()
        .iter(world)
        .fold((0u64, 0u64), |(b, w), f| {
            (b + f.progress.blocked_ticks, w + f.progress.withdrawn)
        });
    if blocked > 0 {
        notes.push(format!(
            "the spaghetti factory's inlet was blocked for {blocked} ticks: its rollers stood still"
        ));
    }
    if withdrawn > 0 {
        notes.push(format!(
            "the spaghetti factory withdrew {withdrawn} lone first particles from its blocked inlet"
        ));
    }
    for drain in world.query::<&Drain>().iter(world) {
        if drain.strands_drained > 0 {
            notes.push(format!(
                "the drain took out {} strands ({} particles) to keep {} particles at most",
                drain.strands_drained, drain.particles_drained, drain.spec.max_particles
            ));
        }
    }
    let simulated = world.resource::<SimulationClock>().time - start_time;
    let mut report = report(
        world,
        &scene,
        (wall_seconds, particle_steps, simulated),
        &ledger,
    );
    report.notes.splice(0..0, notes);
    if let Some(recorder) = recorder {
        let frames = recorder.finish()?;
        for (kind, path) in [("GIF", &options.gif), ("PNG frames", &options.frames)] {
            if let Some(path) = path {
                report
                    .pictures
                    .push(format!("{kind}: {} ({frames} frames)", path.display()));
            }
        }
    }
    if let Some(path) = &options.plot {
        let history = world.resource::<LengthErrorHistory>();
        plot_length_error(path, &scene.name, &history.samples, (900, 500))?;
        report.pictures.push(format!("plot: {}", path.display()));
    }
    Ok(report)
}

/// The guard's first event as the runner's error, the particle named by its strand and
/// its place in it.
fn non_finite_error(world: &World, event: &NonFiniteState) -> RunError {
    let entity = event.particle;
    let topology = world.resource::<Topology>();
    let place = event.strand.and_then(|of| {
        let strand = topology.strands.iter().position(|r| r.entity == of)?;
        let index = (world.get::<Strand>(of)?.particles.iter()).position(|&p| p == entity)?;
        Some(format!("strand {strand}, particle {index}"))
    });
    let place = place.unwrap_or_else(|| format!("particle {entity} (in no strand)"));
    // Values this far out print as thousands of digits otherwise.
    let number = |x: f64| {
        if x.abs() < 1e6 {
            format!("{x}")
        } else {
            format!("{x:e}")
        }
    };
    let time = if event.time.abs() < 1e6 {
        format!("{:.6}", event.time)
    } else {
        number(event.time)
    };
    RunError::NonFinite {
        step: event.step,
        time,
        stage: format!("{:?}", event.stage),
        what: format!(
            "{place} has {} ({}, {})",
            event.quantity.name(),
            number(event.value.x),
            number(event.value.y)
        ),
    }
}

/// The report of a run: `timing` is its wall seconds, particle-steps and simulated
/// seconds.
fn report(
    world: &World,
    scene: &Scenario,
    timing: (f64, u64, f64),
    ledger: &EnergyLedger,
) -> Report {
    let (wall_seconds, particle_steps, simulated) = timing;
    let metrics = world.resource::<StrandMetrics>();
    let clock = world.resource::<SimulationClock>();
    let solver = world.resource::<ConstraintConfig>().solver;
    let islands = world.resource::<Islands>();
    let island_report = IslandReport {
        path: islands.count(IslandKind::Path),
        cycle: islands.count(IslandKind::Cycle),
        tree: islands.count(IslandKind::Tree),
        graph: islands.count(IslandKind::Graph),
        unsolved: islands.unsolved.len(),
        solvers: [
            IslandKind::Path,
            IslandKind::Cycle,
            IslandKind::Tree,
            IslandKind::Graph,
        ]
        .into_iter()
        .filter(|&kind| islands.count(kind) > 0)
        .map(|kind| {
            let method = solver.method(kind).unwrap_or("none: stretch springs");
            format!("{}: {method}", kind.name())
        })
        .collect(),
    };
    let mut notes = Vec::new();
    if solver == SolverKind::Springs {
        notes.push(
            "solver springs: no constraints; every edge is a stretch spring, so lengths \
             follow the spring stiffness"
                .to_string(),
        );
    }
    if solver.relaxation().is_some() {
        let sweeps = world.resource::<ConstraintConfig>().max_iterations;
        notes.push(format!(
            "solver {solver}: a relaxation baseline, {sweeps} sweeps per step at most; \
             contacts are left to the collision impulses, not fed back into the solve"
        ));
    }
    if !world.resource::<CollisionConfig>().enabled {
        notes.push(
            "collisions are off in this run: edges may pass through each other, and \
             edge_crossings counts the steps at which some did"
                .to_string(),
        );
    }
    if metrics.edge_crossings.is_none() {
        notes.push("edge crossings were not checked (--no-check)".to_string());
    }
    // Exact and uncrossed, but not by the contact physics: say so when it is common.
    let steps = world.resource::<SimulationClock>().steps;
    if metrics.failsafe_steps > 0 && metrics.failsafe_steps * 10 >= steps {
        notes.push(format!(
            "{} of {steps} steps ended in the collision fail-safe: impact zones moved \
             rigidly, which keeps every edge and every side but stops or turns whole \
             strands instead of resolving the contacts; the step is too large for the \
             motion, or the forces too large for the step",
            metrics.failsafe_steps
        ));
    }
    if let Some(last) = &metrics.last_unresolved {
        notes.push(format!(
            "{} collisions were left unresolved by the fail-safe (kinematic particles driven into each other); the latest at step {}: point {} against the edge {}–{}{}",
            metrics.unresolved_collisions,
            last.step,
            last.particles[0],
            last.particles[1],
            last.particles[2],
            last.driven_by
                .map_or(String::new(), |e| format!(", driven by the pinned particle {e}"))
        ));
    }
    let first_crossing = metrics
        .first_crossing
        .map(|event| CrossingReport::describe(&event, world.resource::<Topology>()));
    let input_problems = world
        .resource::<InputProblems>()
        .entries
        .iter()
        .map(|p| format!("{}: {}", p.entity, p.problem))
        .collect();
    let free_speeds = FreeSpeeds::of(world);
    Report {
        scenario: scene.name.clone(),
        config: serde_json::to_value(scene).expect("a scenario always serializes"),
        solver: solver.name().to_string(),
        steps: clock.steps,
        sim_time: clock.time,
        particles: metrics.particles,
        strands: metrics.strands,
        constrained_edges: metrics.constrained_edges,
        islands: island_report,
        max_rel_length_error: metrics.max_rel_length_error,
        max_rel_length_error_free: metrics.max_rel_length_error_free,
        max_speed_at_end: world
            .resource::<ParticleState>()
            .velocity
            .iter()
            .map(|v| v.length())
            .fold(0.0, f64::max),
        median_speed_at_end: free_speeds.quantile(0.5),
        p95_speed_at_end: free_speeds.quantile(0.95),
        energy_start: ledger.start.unwrap_or(ledger.end),
        energy_end: ledger.end,
        energy_gained: ledger.largest_rise,
        driven_ticks: ledger.driven_ticks,
        edge_crossings: metrics.edge_crossings,
        first_crossing,
        contacts: metrics.contacts,
        collisions: metrics.collisions,
        failsafe_steps: metrics.failsafe_steps,
        halved_steps: metrics.halved_steps,
        split_steps: metrics.split_steps,
        asleep_particles: metrics.asleep_particles,
        sleeps: metrics.sleeps,
        wakes: metrics.wakes,
        projection_iterations_mean: metrics.projection.mean(),
        projection_iterations_max: metrics.projection.max,
        projection_capped_solves: metrics.projection.capped,
        projection_restepped_solves: metrics.projection.restepped,
        projection_substeps: metrics.projection.substeps,
        contact_projection_solves: metrics.contact_projection.solves,
        contact_projection_newton_solves: metrics.contact_projection.newton_solves,
        contact_projection_factorizations: metrics.contact_projection.factorizations,
        contact_projection_escalated: metrics.contact_projection.escalated,
        contact_projection_iterations_mean: metrics.contact_projection.mean(),
        contact_projection_iterations_max: metrics.contact_projection.max,
        contact_projection_capped_solves: metrics.contact_projection.capped,
        contact_projection_rejected_solves: metrics.contact_projection.rejected,
        contact_unsettled_steps: metrics.contact_unsettled_steps,
        threads: world.resource::<StrandsConfig>().worker_threads(),
        wall_seconds,
        particle_steps_per_second: if wall_seconds > 0.0 {
            particle_steps as f64 / wall_seconds
        } else {
            0.0
        },
        real_time_factor: if wall_seconds > 0.0 {
            simulated / wall_seconds
        } else {
            0.0
        },
        notes,
        input_problems,
        pictures: Vec::new(),
        stage_profile: world
            .get_resource::<StageProfile>()
            .map(|profile| profile.shares(wall_seconds))
            .unwrap_or_default(),
    }
}
