//! Component hooks: adding or removing a particle, a pin or a strand marks the topology
//! for a rebuild at the start of the next tick. The flag is a resource of its own so
//! that the components need to know nothing of the topology built from them.

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
