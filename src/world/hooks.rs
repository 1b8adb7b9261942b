//! Component hooks: adding or removing a particle, a pin or a strand marks the topology
//! for a rebuild at the start of the next tick. The flag is a resource of its own so
//! that the components need to know nothing of the topology built from them. Particles
//! and strands are also numbered in the order they arrive ([`SpawnOrder`]).

use std::cmp::Reverse;

use bevy::ecs::entity::EntityHashMap;
use bevy::ecs::lifecycle::HookContext;
use bevy::ecs::world::DeferredWorld;
use bevy::prelude::*;

/// Whether the topology must be rebuilt before the next step.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TopologyDirty(pub bool);

impl TopologyDirty {
    /// Ask for a rebuild at the start of the next tick.
    pub fn mark(&mut self) {
        self.0 = true;
    }
}

/// The hook of every component whose presence changes the topology.
pub(crate) fn on_structure_changed(mut world: DeferredWorld, _: HookContext) {
    if let Some(mut dirty) = world.get_resource_mut::<TopologyDirty>() {
        dirty.0 = true;
    }
}

/// The order particles and strands came into the world: a serial number each, from a
/// counter that only grows.
///
/// The topology rebuild and snapshots order strands and loose particles by it, newest
/// first. Not by the entities themselves: Bevy gives a despawned entity's slot to a
/// later spawn, so after a despawn the entities' order depends on the history of
/// the allocator, which a world restored from a snapshot does not share, and the
/// solve order — and with it every sum of a step — would differ. Newest first is
/// the order fresh entities have by their own `Ord`.
#[derive(Resource, Clone, Debug, Default)]
pub struct SpawnOrder {
    next: u64,
    strands: EntityHashMap<u64>,
    particles: EntityHashMap<u64>,
}

/// How [`SpawnOrder`] sorts: newest first, then (for entities spawned before the
/// resource existed, which have no serial) by entity.
pub type SpawnKey = (Reverse<Option<u64>>, Entity);

impl SpawnOrder {
    /// The sort key of a strand entity.
    pub fn strand_key(&self, strand: Entity) -> SpawnKey {
        (Reverse(self.strands.get(&strand).copied()), strand)
    }

    /// The sort key of a particle entity.
    pub fn particle_key(&self, particle: Entity) -> SpawnKey {
        (Reverse(self.particles.get(&particle).copied()), particle)
    }

    fn number(&mut self, entity: Entity, strand: bool) {
        let next = self.next;
        let map = if strand {
            &mut self.strands
        } else {
            &mut self.particles
        };
        if let bevy::platform::collections::hash_map::Entry::Vacant(slot) = map.entry(entity) {
            slot.insert(next);
            self.next += 1;
        }
    }
}

/// `Strand` inserted: the topology changes, and a new strand gets its serial.
pub(crate) fn on_strand_inserted(mut world: DeferredWorld, context: HookContext) {
    on_structure_changed(world.reborrow(), context);
    if let Some(mut order) = world.get_resource_mut::<SpawnOrder>() {
        order.number(context.entity, true);
    }
}

/// `Particle` added: likewise.
pub(crate) fn on_particle_added(mut world: DeferredWorld, context: HookContext) {
    on_structure_changed(world.reborrow(), context);
    if let Some(mut order) = world.get_resource_mut::<SpawnOrder>() {
        order.number(context.entity, false);
    }
}

/// `Strand` removed: its serial goes with it.
pub(crate) fn on_strand_removed(mut world: DeferredWorld, context: HookContext) {
    on_structure_changed(world.reborrow(), context);
    if let Some(mut order) = world.get_resource_mut::<SpawnOrder>() {
        order.strands.remove(&context.entity);
    }
}

/// `Particle` removed: likewise.
pub(crate) fn on_particle_removed(mut world: DeferredWorld, context: HookContext) {
    on_structure_changed(world.reborrow(), context);
    if let Some(mut order) = world.get_resource_mut::<SpawnOrder>() {
        order.particles.remove(&context.entity);
    }
}
