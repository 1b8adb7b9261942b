//! Run snapshots: everything needed to continue a scenario run from a tick — the
//! scenario, the simulated state, how far the factories have got, and the figures so
//! far — as one RON file. `strands run … --snapshot-at T --snapshot FILE` writes one;
//! `strands run --from FILE` continues from it, bit for bit as the original run did.

use std::path::Path;

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::metrics::StrandMetrics;
use bevy_strands::snapshot::{SnapshotEntities, SnapshotError, StrandsSnapshot};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::scenario::Scenario;
use crate::scenes::drain::Drain;
use crate::scenes::furry_creature::FurryCreature;
use crate::scenes::meatball_factory::{MeatballFactory, MeatballProgress};
use crate::scenes::spaghetti_factory::{SpaghettiFactory, SpaghettiProgress};
use crate::spawn::configure;

/// A spaghetti factory's progress, its particles and strand by their snapshot numbers.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct SpaghettiProgressRecord {
    /// Simulated time of the next emission.
    pub next_emission: f64,
    /// Strands finished or in progress.
    pub strands_started: usize,
    /// Particles of the strand being extruded, oldest first.
    pub current: Vec<u32>,
    /// Its strand, once it has two particles.
    pub current_strand: Option<u32>,
    /// Whether the inlet is blocked.
    #[serde(default)]
    pub blocked: bool,
    /// Ticks the inlet has been blocked, in all.
    #[serde(default)]
    pub blocked_ticks: u64,
    /// Lone particles withdrawn from the blocked inlet.
    #[serde(default)]
    pub withdrawn: u64,
}

/// A furry creature's driven particles, by snapshot number, with their offsets.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct FurryRootsRecord {
    /// Each driven particle and its offset from the body's centre.
    pub roots: Vec<(u32, DVec2)>,
}

/// A run captured at the end of a tick.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct RunSnapshot {
    /// The scenario being run (its settings and the factories' specs).
    pub scenario: Scenario,
    /// Particles, strands and the clock.
    pub state: StrandsSnapshot,
    /// The spaghetti factory's progress, if the scenario has one.
    #[serde(default)]
    pub spaghetti_factory: Option<SpaghettiProgressRecord>,
    /// The meatball factory's progress, if the scenario has one.
    #[serde(default)]
    pub meatball_factory: Option<MeatballProgress>,
    /// The furry creature's roots, if the scenario has one.
    #[serde(default)]
    pub furry_creature: Option<FurryRootsRecord>,
    /// The figures so far.
    #[serde(default)]
    pub metrics: StrandMetrics,
}

/// Why a snapshot could not be written or restored.
#[derive(Debug, Error)]
pub enum RunSnapshotError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// What went wrong.
        source: std::io::Error,
    },
    /// The file is not a snapshot.
    #[error("{path}: {problem}")]
    Format {
        /// The file.
        path: String,
        /// What is wrong.
        problem: String,
    },
    /// The snapshot is inconsistent.
    #[error("{path}: {source}")]
    State {
        /// The file.
        path: String,
        /// What is wrong.
        source: SnapshotError,
    },
}

impl RunSnapshot {
    /// Capture the run of `scenario` in `world`.
    pub fn capture(world: &mut World, scenario: &Scenario) -> RunSnapshot {
        let (state, entities) = StrandsSnapshot::capture(world);
        let number = |e: Entity| entities.particle_number(e).unwrap_or(u32::MAX);
        let spaghetti_factory = world
            .query::<&SpaghettiFactory>()
            .iter(world)
            .next()
            .map(|f| SpaghettiProgressRecord {
                next_emission: f.progress.next_emission,
                strands_started: f.progress.strands_started,
                current: f.progress.current.iter().map(|&p| number(p)).collect(),
                current_strand: f
                    .progress
                    .current_strand
                    .and_then(|s| entities.strand_number(s)),
                blocked: f.progress.blocked,
                blocked_ticks: f.progress.blocked_ticks,
                withdrawn: f.progress.withdrawn,
            });
        let meatball_factory = world
            .query::<&MeatballFactory>()
            .iter(world)
            .next()
            .map(|f| f.progress);
        let furry_creature =
            world
                .query::<&FurryCreature>()
                .iter(world)
                .next()
                .map(|c| FurryRootsRecord {
                    roots: c.roots.iter().map(|&(p, o)| (number(p), o)).collect(),
                });
        RunSnapshot {
            scenario: scenario.clone(),
            state,
            spaghetti_factory,
            meatball_factory,
            furry_creature,
            metrics: world.resource::<StrandMetrics>().clone(),
        }
    }

    /// Configure `world` for the scenario and restore the state, the factories and the
    /// figures. `world` must hold no particle or strand yet.
    pub fn restore(&self, world: &mut World) -> Result<SnapshotEntities, SnapshotError> {
        configure(world, &self.scenario);
        let entities = self.state.restore(world)?;
        let particle = |p: u32| {
            entities
                .particles
                .get(p as usize)
                .copied()
                .ok_or(SnapshotError::UnknownParticle(p))
        };
        if let (Some(spec), Some(progress)) =
            (self.scenario.spaghetti_factory, &self.spaghetti_factory)
        {
            let mut factory = SpaghettiFactory::new(spec);
            factory.progress = SpaghettiProgress {
                next_emission: progress.next_emission,
                strands_started: progress.strands_started,
                current: progress
                    .current
                    .iter()
                    .map(|&p| particle(p))
                    .collect::<Result<_, _>>()?,
                current_strand: progress
                    .current_strand
                    .and_then(|s| entities.strands.get(s as usize).copied()),
                blocked: progress.blocked,
                blocked_ticks: progress.blocked_ticks,
                withdrawn: progress.withdrawn,
            };
            world.spawn(factory);
        }
        if let (Some(spec), Some(progress)) =
            (self.scenario.meatball_factory, self.meatball_factory)
        {
            world.spawn(MeatballFactory { spec, progress });
        }
        if let Some(spec) = self.scenario.drain {
            // The drain keeps no state: its spec is all it needs.
            world.spawn(Drain::new(spec));
        }
        if let (Some(spec), Some(record)) = (self.scenario.furry_creature, &self.furry_creature) {
            let roots = record
                .roots
                .iter()
                .map(|&(p, offset)| particle(p).map(|e| (e, offset)))
                .collect::<Result<_, _>>()?;
            let creature = FurryCreature::new(spec, roots);
            let disc = creature.disc(self.state.clock.time);
            world.spawn((creature, disc));
        }
        let mut metrics = self.metrics.clone();
        // The per-edge errors belong to the captured topology; the next step refills them.
        metrics.relative_length_error.clear();
        world.insert_resource(metrics);
        Ok(entities)
    }

    /// Write the snapshot as RON.
    pub fn save(&self, path: &Path) -> Result<(), RunSnapshotError> {
        let name = path.display().to_string();
        // One particle or strand a line: readable, and a third of the fully indented size.
        let pretty = ron::ser::PrettyConfig::default()
            .depth_limit(3)
            .separate_tuple_members(false);
        let text =
            ron::ser::to_string_pretty(self, pretty).map_err(|e| RunSnapshotError::Format {
                path: name.clone(),
                problem: e.to_string(),
            })?;
        std::fs::write(path, text).map_err(|source| RunSnapshotError::Io { path: name, source })
    }

    /// Read a snapshot written by [`RunSnapshot::save`], checking that it is consistent.
    pub fn load(path: &Path) -> Result<RunSnapshot, RunSnapshotError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| RunSnapshotError::Io {
            path: name.clone(),
            source,
        })?;
        let snapshot: RunSnapshot = ron::from_str(&text).map_err(|e| RunSnapshotError::Format {
            path: name.clone(),
            problem: format!(
                "line {}, column {}: {}",
                e.span.start.line, e.span.start.col, e.code
            ),
        })?;
        snapshot
            .scenario
            .validate(&name)
            .map_err(|e| RunSnapshotError::Format {
                path: name.clone(),
                problem: e.to_string(),
            })?;
        snapshot
            .state
            .check()
            .map_err(|source| RunSnapshotError::State { path: name, source })?;
        Ok(snapshot)
    }
}
