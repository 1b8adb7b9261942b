//! Where a run's wall time goes, stage by stage (`strands run --profile`).
//!
//! Marker systems sit between the sets of a tick ([`TickSet`]) and of a step
//! ([`StepSet`], [`ConstrainSet`], [`CollideSet`]), which run in a fixed order; each
//! marker reads the clock, and the time between two consecutive markers is the stage
//! between them. The markers only read the clock and write their own resource, so they
//! change nothing the simulation computes; what they cost (two clock reads a stage) is
//! in the figures.

use bevy::ecs::schedule::{InternedSystemSet, ScheduleLabel};
use bevy::platform::time::Instant;
use bevy::prelude::*;
use bevy_strands::schedule::{
    CollideSet, ConstrainSet, StepSet, StrandsStep, StrandsTick, TickSet,
};
use serde::Serialize;

/// The phases of a tick, as the report names them.
const TICK_STAGES: [&str; 6] = [
    "tick: scene logic",
    "tick: sleeping and waking",
    "tick: topology",
    "tick: gather",
    "tick: steps",
    "tick: write-back",
];

/// The stages of a step, as the report names them.
const STEP_STAGES: [&str; 10] = [
    "step: forces",
    "step: predict",
    "step: edge projection",
    "step: contact solve",
    "step: proximity",
    "step: impulses",
    "step: contact loop",
    "step: collision figures",
    "step: integrate",
    "step: measure",
];

/// One stage's share of a run's wall time.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct StageShare {
    /// The stage.
    pub stage: String,
    /// Its wall seconds over the run.
    pub seconds: f64,
    /// Its share of the ticks' wall time.
    pub share: f64,
}

/// Wall seconds between consecutive markers of one schedule.
#[derive(Debug, Default)]
struct StageClock {
    totals: Vec<f64>,
    last: Option<(usize, Instant)>,
}

impl StageClock {
    fn mark(&mut self, index: usize, count: usize) {
        let now = Instant::now();
        if self.totals.len() < count {
            self.totals.resize(count, 0.0);
        }
        // Only a stage whose start was marked just before counts: a phase skipped
        // (a paused tick) adds nothing.
        if let Some((previous, at)) = self.last
            && index == previous + 1
        {
            self.totals[previous] += now.duration_since(at).as_secs_f64();
        }
        self.last = Some((index, now));
    }
}

/// The markers' clocks: the tick's phases and the step's stages.
#[derive(Resource, Debug, Default)]
pub struct StageProfile {
    tick: StageClock,
    step: StageClock,
}

impl StageProfile {
    /// Each stage's wall seconds and share of `wall_seconds` (the ticks' total): the
    /// tick's phases, then the step's stages, then what the steps' phase spent outside
    /// them (step halving's copies, the guard between stages, the step loop).
    pub fn shares(&self, wall_seconds: f64) -> Vec<StageShare> {
        let tick = |k: usize| self.tick.totals.get(k).copied().unwrap_or(0.0);
        let step = |k: usize| self.step.totals.get(k).copied().unwrap_or(0.0);
        let in_steps: f64 = (0..STEP_STAGES.len()).map(step).sum();
        let share = |seconds: f64| {
            if wall_seconds > 0.0 {
                seconds / wall_seconds
            } else {
                0.0
            }
        };
        let mut rows: Vec<(&str, f64)> = TICK_STAGES
            .iter()
            .enumerate()
            .map(|(k, &name)| (name, tick(k)))
            .collect();
        rows.extend(
            STEP_STAGES
                .iter()
                .enumerate()
                .map(|(k, &name)| (name, step(k))),
        );
        rows.push((
            "step: between stages (halving, guard, loop)",
            (tick(4) - in_steps).max(0.0),
        ));
        rows.into_iter()
            .map(|(stage, seconds)| StageShare {
                stage: stage.to_string(),
                seconds,
                share: share(seconds),
            })
            .collect()
    }
}

/// Add the markers to `app`'s schedules (before or after the app is finished).
pub fn add_stage_markers(app: &mut App) {
    app.init_resource::<StageProfile>();
    let tick: [InternedSystemSet; 6] = [
        TickSet::Prepare.intern(),
        TickSet::Sleep.intern(),
        TickSet::Topology.intern(),
        TickSet::Gather.intern(),
        TickSet::Step.intern(),
        TickSet::Writeback.intern(),
    ];
    let step: [InternedSystemSet; 10] = [
        StepSet::Forces.intern(),
        StepSet::Predict.intern(),
        ConstrainSet::Project.intern(),
        ConstrainSet::Speculate.intern(),
        CollideSet::Proximity.intern(),
        CollideSet::Impulses.intern(),
        CollideSet::ContactLoop.intern(),
        CollideSet::Account.intern(),
        StepSet::Integrate.intern(),
        StepSet::Measure.intern(),
    ];
    markers(app, StrandsTick, &tick, |p| &mut p.tick);
    markers(app, StrandsStep, &step, |p| &mut p.step);
}

/// A marker before each of `sets` and one after the last: marker `k` starts stage `k`.
fn markers(
    app: &mut App,
    schedule: impl ScheduleLabel + Clone,
    sets: &[InternedSystemSet],
    clock: fn(&mut StageProfile) -> &mut StageClock,
) {
    let count = sets.len();
    for k in 0..=count {
        let marker = move |mut profile: ResMut<StageProfile>| clock(&mut profile).mark(k, count);
        let config = marker.into_configs();
        let config = match (k.checked_sub(1).map(|j| sets[j]), sets.get(k)) {
            (Some(before), Some(&after)) => config.after(before).before(after),
            (None, Some(&after)) => config.before(after),
            (Some(before), None) => config.after(before),
            (None, None) => config,
        };
        app.add_systems(schedule.clone(), config);
    }
}
