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

/// The phases of a tick in their order, each with the name the report gives it.
fn tick_stages() -> [(&'static str, InternedSystemSet); 6] {
    [
        ("tick: scene logic", TickSet::Prepare.intern()),
        ("tick: sleeping and waking", TickSet::Sleep.intern()),
        ("tick: topology", TickSet::Topology.intern()),
        ("tick: gather", TickSet::Gather.intern()),
        (STEPS, TickSet::Step.intern()),
        ("tick: write-back", TickSet::Writeback.intern()),
    ]
}

/// The tick's phase that runs the steps.
const STEPS: &str = "tick: steps";

/// The stages of a step in their order, each with the name the report gives it.
fn step_stages() -> [(&'static str, InternedSystemSet); 10] {
    [
        ("step: forces", StepSet::Forces.intern()),
        ("step: predict", StepSet::Predict.intern()),
        ("step: edge projection", ConstrainSet::Project.intern()),
        ("step: contact solve", ConstrainSet::Speculate.intern()),
        ("step: proximity", CollideSet::Proximity.intern()),
        ("step: impulses", CollideSet::Impulses.intern()),
        ("step: contact loop", CollideSet::ContactLoop.intern()),
        ("step: collision figures", CollideSet::Account.intern()),
        ("step: integrate", StepSet::Integrate.intern()),
        ("step: measure", StepSet::Measure.intern()),
    ]
}

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
        let timed = |stages: &[(&'static str, InternedSystemSet)], clock: &StageClock| {
            let total = |k: usize| clock.totals.get(k).copied().unwrap_or(0.0);
            (stages.iter().enumerate())
                .map(|(k, &(name, _))| (name, total(k)))
                .collect::<Vec<_>>()
        };
        let mut rows = timed(&tick_stages(), &self.tick);
        let steps = rows.iter().find(|r| r.0 == STEPS).map_or(0.0, |r| r.1);
        let stages = timed(&step_stages(), &self.step);
        let in_stages: f64 = stages.iter().map(|r| r.1).sum();
        rows.extend(stages);
        rows.push((
            "step: between stages (halving, guard, loop)",
            (steps - in_stages).max(0.0),
        ));
        rows.into_iter()
            .map(|(stage, seconds)| StageShare {
                stage: stage.to_string(),
                seconds,
                share: if wall_seconds > 0.0 {
                    seconds / wall_seconds
                } else {
                    0.0
                },
            })
            .collect()
    }
}

/// Add the markers to `app`'s schedules (before or after the app is finished).
pub fn add_stage_markers(app: &mut App) {
    app.init_resource::<StageProfile>();
    markers(app, StrandsTick, &tick_stages(), |p| &mut p.tick);
    markers(app, StrandsStep, &step_stages(), |p| &mut p.step);
}

/// A marker before each of `sets` and one after the last: marker `k` starts stage `k`.
fn markers(
    app: &mut App,
    schedule: impl ScheduleLabel + Clone,
    stages: &[(&'static str, InternedSystemSet)],
    clock: fn(&mut StageProfile) -> &mut StageClock,
) {
    let sets: Vec<InternedSystemSet> = stages.iter().map(|&(_, set)| set).collect();
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
