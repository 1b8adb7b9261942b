//! Contact messages for gameplay: when two strands (or a strand and a collider, or a
//! loose particle) start and stop touching. A pair touches in a tick if, in any of its
//! steps, a point of one met an edge of the other in the collision stage (an impulse,
//! proximity or continuous). At each tick's end the pairs are compared with the last
//! tick's: each new pair is a [`StrandContact::Started`], each pair gone a
//! [`StrandContact::Ended`], in a fixed order.

use bevy::prelude::*;

use crate::colliders::ColliderOf;
use crate::collision::CollisionScratch;
use crate::collision::plugin::check_crossings;
use crate::halving::HalvingApp;
use crate::schedule::{StepSet, StrandsStep, StrandsTick, TickSet, stepping};
use crate::world::state::{ParticleState, copy_buffer};
use crate::world::strand::StrandOf;
use crate::world::topology::Topology;

/// Two bodies started or stopped touching: strands, by their entity; a collider's
/// outline, by the collider's entity; a loose particle, by its own.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrandContact {
    /// They touch this tick and did not the last.
    Started(Entity, Entity),
    /// They touched the last tick and do not this one.
    Ended(Entity, Entity),
}

/// The pairs touching in the current and the last tick (each pair ordered). Plain
/// vectors, sorted at the tick's end, so a steady contact allocates nothing.
#[derive(Resource, Default, Debug)]
pub struct TouchingPairs {
    /// This tick's so far, sorted and without repeats.
    pub current: Vec<(Entity, Entity)>,
    /// The last tick's, sorted and without repeats.
    pub previous: Vec<(Entity, Entity)>,
}

/// Collects the pairs every step and writes the messages every tick.
pub struct ContactEventsPlugin;

impl Plugin for ContactEventsPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<TouchingPairs>()
            .save_for_halving::<TouchingPairs, Vec<(Entity, Entity)>>(
                |pairs, current| {
                    // The two lists trade places every tick: room for the longer.
                    let room = pairs.current.capacity().max(pairs.previous.capacity());
                    if current.capacity() < room {
                        current.reserve(room);
                    }
                    copy_buffer(current, &pairs.current);
                },
                |pairs, current| copy_buffer(&mut pairs.current, current),
            )
            .add_message::<StrandContact>()
            .add_systems(
                StrandsStep,
                collect_pairs
                    .in_set(StepSet::Measure)
                    .before(check_crossings),
            )
            .add_systems(
                StrandsTick,
                write_messages.after(TickSet::Writeback).run_if(stepping),
            );
    }
}

/// The body a packed particle belongs to.
fn body(
    i: usize,
    state: &ParticleState,
    owners: &Query<&StrandOf>,
    colliders: &Query<&ColliderOf>,
) -> Option<Entity> {
    let particle = *state.entity.get(i)?;
    let Ok(owner) = owners.get(particle) else {
        return Some(particle);
    };
    Some(colliders.get(owner.0).map_or(owner.0, |c| c.0))
}

fn collect_pairs(
    scratch: Res<CollisionScratch>,
    state: Res<ParticleState>,
    topology: Res<Topology>,
    owners: Query<&StrandOf>,
    colliders: Query<&ColliderOf>,
    mut pairs: ResMut<TouchingPairs>,
) {
    // As large as the contacts' buffer: it grows when that does, not at a later step.
    let room = scratch.impulses.contacts.capacity();
    let len = pairs.current.len();
    pairs.current.reserve(room.saturating_sub(len));
    for contact in &scratch.impulses.contacts {
        let Some(edge) = topology.edges.get(contact.edge as usize) else {
            continue;
        };
        let a = body(contact.p as usize, &state, &owners, &colliders);
        let b = body(edge.a as usize, &state, &owners, &colliders);
        if let (Some(a), Some(b)) = (a, b)
            && a != b
        {
            pairs.current.push((a.min(b), a.max(b)));
        }
    }
    // Kept sorted and without repeats step by step, so its length stays the number of
    // pairs however many steps a tick has.
    pairs.current.sort_unstable();
    pairs.current.dedup();
}

pub(crate) fn write_messages(
    mut pairs: ResMut<TouchingPairs>,
    mut messages: MessageWriter<StrandContact>,
) {
    let pairs = &mut *pairs;
    // Started pairs, then ended ones, each in order.
    let (now, before) = (&pairs.current, &pairs.previous);
    for pair in now.iter().filter(|p| before.binary_search(p).is_err()) {
        messages.write(StrandContact::Started(pair.0, pair.1));
    }
    for pair in before.iter().filter(|p| now.binary_search(p).is_err()) {
        messages.write(StrandContact::Ended(pair.0, pair.1));
    }
    std::mem::swap(&mut pairs.previous, &mut pairs.current);
    pairs.current.clear();
}
