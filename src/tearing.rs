//! Tearing: a strand with [`Tearable`] whose tension in the last step of a tick passed
//! its limit somewhere is cut at its most tensioned edge (see
//! [`Islands::edge_tension`]) — one cut a strand a tick, as a rope parts at one place
//! and the tension everywhere else drops with it.

use bevy::prelude::*;

use crate::constraints::Islands;
use crate::schedule::{StrandsTick, TickSet, stepping};
use crate::world::config::StrandsConfig;
use crate::world::strand::{Strand, StrandOf};
use crate::world::topology::{Topology, cut_strand};

/// Cut this strand's edges that pull harder than `max_tension` (newtons).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct Tearable {
    /// The tension an edge survives.
    pub max_tension: f64,
}

/// A strand edge that tore.
#[derive(Message, Clone, Copy, Debug, PartialEq)]
pub struct StrandTorn {
    /// The strand (its first piece keeps this entity).
    pub strand: Entity,
    /// The edge's number along the strand before the cut.
    pub edge: usize,
    /// Its tension when it tore.
    pub tension: f64,
}

/// Tears strands.
pub struct TearingPlugin;

impl Plugin for TearingPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<Tearable>()
            .add_message::<StrandTorn>()
            .add_systems(StrandsTick, tear.after(TickSet::Writeback).run_if(stepping));
    }
}

fn tear(
    config: Res<StrandsConfig>,
    islands: Res<Islands>,
    topology: Res<Topology>,
    tearable: Query<(Entity, &Tearable)>,
    mut commands: Commands,
) {
    for (strand, tearable) in &tearable {
        let Some(record) = topology.strands.iter().find(|r| r.entity == strand) else {
            continue;
        };
        // The most tensioned edge; of equals, the first.
        let most = record
            .edges
            .clone()
            .enumerate()
            .map(|(k, edge)| (k, islands.edge_tension(edge, config.dt)))
            .fold(None, |best: Option<(usize, f64)>, (k, t)| match best {
                Some((_, b)) if b >= t => best,
                _ => Some((k, t)),
            });
        if let Some((edge, tension)) = most.filter(|&(_, t)| t > tearable.max_tension) {
            let event = StrandTorn {
                strand,
                edge,
                tension,
            };
            let limit = *tearable;
            commands.queue(move |world: &mut World| {
                // The particle past the cut: a new piece owns it afterwards, and tears
                // as the strand it came from.
                let beyond = world
                    .get::<Strand>(event.strand)
                    .and_then(|s| s.particles.get(event.edge + 1).copied());
                if cut_strand(world, event.strand, event.edge).is_some() {
                    let piece = beyond.and_then(|p| world.get::<StrandOf>(p)).map(|of| of.0);
                    if let Some(piece) = piece.filter(|&piece| piece != event.strand) {
                        world.entity_mut(piece).insert(limit);
                    }
                    world.write_message(event);
                }
            });
        }
    }
}
