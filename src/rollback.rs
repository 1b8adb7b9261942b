//! Taking a step again: what a step changes, saved before it so that a step that would
//! end in the collision fail-safe can be put back and taken as two halves.
//!
//! Each area registers the state its step systems carry from one step to the next (the
//! packed particles, the metrics, the clock, the contact warm starts, a body
//! coupling's impulses); buffers rebuilt every step are not saved.

use bevy::ecs::component::Mutable;
use bevy::prelude::*;

type Restore = Box<dyn FnOnce(&mut World) + Send>;
type Take = Box<dyn Fn(&World) -> Option<Restore> + Send + Sync>;

/// The state a step carries forward, as registered by each area's plugin.
#[derive(Resource, Default)]
pub struct StepRollback {
    takers: Vec<Take>,
    vetoes: Vec<fn(&World) -> bool>,
}

impl std::fmt::Debug for StepRollback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StepRollback")
            .field("registered", &self.takers.len())
            .finish()
    }
}

/// What [`StepRollback::save`] saved: put it back with [`Saved::restore`].
pub struct Saved(Vec<Restore>);

impl StepRollback {
    /// Save the part of resource `T` that `take` returns before each step, put back by
    /// `restore` when the step is taken again.
    pub fn register<T: Resource<Mutability = Mutable>, S: Send + 'static>(
        &mut self,
        take: fn(&T) -> S,
        restore: fn(&mut T, S),
    ) {
        self.takers.push(Box::new(move |world: &World| {
            let saved = take(world.get_resource::<T>()?);
            Some(Box::new(move |world: &mut World| {
                if let Some(mut resource) = world.get_resource_mut::<T>() {
                    restore(&mut resource, saved);
                }
            }) as Restore)
        }));
    }

    /// Save the whole of resource `T`.
    pub fn register_clone<T: Resource<Mutability = Mutable> + Clone>(&mut self) {
        self.register::<T, T>(T::clone, |resource, saved| *resource = saved);
    }

    /// Never take a step again while `veto` says so (state a step cannot put back).
    pub fn forbid_when(&mut self, veto: fn(&World) -> bool) {
        self.vetoes.push(veto);
    }

    /// Whether a step of `world` may be taken again.
    pub fn allows(&self, world: &World) -> bool {
        !self.vetoes.iter().any(|veto| veto(world))
    }

    /// Save every registered resource of `world`.
    pub fn save(&self, world: &World) -> Saved {
        Saved(self.takers.iter().filter_map(|take| take(world)).collect())
    }
}

impl Saved {
    /// Put every saved resource back as it was.
    pub fn restore(self, world: &mut World) {
        for restore in self.0 {
            restore(world);
        }
    }
}

/// Registering state with [`StepRollback`] from a plugin.
pub trait RollbackApp {
    /// See [`StepRollback::register`].
    fn roll_back<T: Resource<Mutability = Mutable>, S: Send + 'static>(
        &mut self,
        take: fn(&T) -> S,
        restore: fn(&mut T, S),
    ) -> &mut Self;
    /// See [`StepRollback::register_clone`].
    fn roll_back_clone<T: Resource<Mutability = Mutable> + Clone>(&mut self) -> &mut Self;
}

impl RollbackApp for App {
    fn roll_back<T: Resource<Mutability = Mutable>, S: Send + 'static>(
        &mut self,
        take: fn(&T) -> S,
        restore: fn(&mut T, S),
    ) -> &mut Self {
        self.init_resource::<StepRollback>();
        self.world_mut()
            .resource_mut::<StepRollback>()
            .register(take, restore);
        self
    }

    fn roll_back_clone<T: Resource<Mutability = Mutable> + Clone>(&mut self) -> &mut Self {
        self.init_resource::<StepRollback>();
        self.world_mut()
            .resource_mut::<StepRollback>()
            .register_clone::<T>();
        self
    }
}
