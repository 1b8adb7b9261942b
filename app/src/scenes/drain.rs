//! The drain: an outlet in the container's floor that keeps a factory's pile bounded.
//!
//! A factory left running fills its box: the spaghetti factory's 1 m box is full after
//! about two minutes, and from then on the pile grows up to the inlet. A game's emitter
//! (and a long soak) needs a steady state instead. While the scene holds more than
//! `max_particles` particles (walls left out), the strand lying lowest — its lowest
//! particle lowest — leaves at the start of a tick, one strand per tick: the pile
//! above it settles into the gap. Strands that are held (a pinned or kinematic
//! particle, the factory's strand being extruded among them) and walls never leave.
//!
//! The drain keeps no state: which strand leaves follows from the positions alone, so a
//! run continued from a snapshot drains the same strands.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use serde::{Deserialize, Serialize};

/// What a drain keeps: the scenario file's `drain` section.
#[derive(Serialize, Deserialize, Reflect, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DrainSpec {
    /// The most particles the scene may hold (walls left out) before the lowest strand
    /// leaves.
    pub max_particles: usize,
}

/// An outlet at the bottom of the pile. Add it to an entity; [`run_drains`] does the rest.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component)]
pub struct Drain {
    /// What it keeps.
    pub spec: DrainSpec,
    /// Strands taken out so far (in this run: a snapshot does not carry it).
    pub strands_drained: u64,
    /// Their particles.
    pub particles_drained: u64,
}

impl Drain {
    /// A drain that has taken nothing out yet.
    pub fn new(spec: DrainSpec) -> Self {
        Self {
            spec,
            strands_drained: 0,
            particles_drained: 0,
        }
    }
}

/// Take the lowest free strand out while the scene holds more particles than a drain
/// allows.
pub fn run_drains(
    mut commands: Commands,
    state: Res<ParticleState>,
    topology: Res<Topology>,
    mut drains: Query<&mut Drain>,
    strands: Query<(Entity, &Strand, Option<&StrandKind>)>,
) {
    if drains.is_empty() {
        return;
    }
    let mut held = 0usize;
    let mut candidates: Vec<(f64, Entity, usize)> = Vec::new();
    for (entity, strand, kind) in &strands {
        if kind == Some(&StrandKind::Wall) {
            continue;
        }
        let mut lowest = f64::INFINITY;
        let mut free = true;
        for p in &strand.particles {
            let i = topology.index.get(p).map(|&i| i as usize);
            match i.zip(i.and_then(|i| state.position.get(i))) {
                Some((i, position)) => {
                    // Pinned, kinematic and frozen particles alike.
                    free &= !topology.pinned.get(i).copied().unwrap_or(true);
                    lowest = lowest.min(position.y);
                }
                // Not simulated yet (spawned this tick) or refused: not the drain's.
                None => free = false,
            }
        }
        held += strand.particles.len();
        if free && lowest.is_finite() {
            candidates.push((lowest, entity, strand.particles.len()));
        }
    }
    for mut drain in &mut drains {
        if held <= drain.spec.max_particles {
            continue;
        }
        // Lowest first; the entity breaks a tie the same way in every run.
        let Some(&(_, strand, particles)) = candidates
            .iter()
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        else {
            continue;
        };
        commands.entity(strand).despawn();
        candidates.retain(|c| c.1 != strand);
        held -= particles;
        drain.strands_drained += 1;
        drain.particles_drained += particles as u64;
    }
}
