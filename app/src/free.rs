//! The free particles at the end of a tick: every particle the solver moves and every
//! sleeping one (at rest), pinned and driven ones aside — what the report's speeds and
//! energy account are taken over.

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::world::particle::SolverIndex;

/// Mark in `free` (one entry per packed particle) the free particles of `world`.
pub fn free_particles(world: &World, free: &mut Vec<bool>) {
    FreeParticles::default().mark(world, free);
}

/// The query of sleeping particles, kept from one call to the next: building it
/// matches every archetype, which every tick of a small scene would pay again.
#[derive(Default)]
pub struct FreeParticles {
    asleep: Option<QueryState<&'static SolverIndex, With<Sleeping>>>,
}

impl FreeParticles {
    /// Mark in `free` (one entry per packed particle) the free particles of `world`.
    pub fn mark(&mut self, world: &World, free: &mut Vec<bool>) {
        let state = world.resource::<ParticleState>();
        free.clear();
        free.extend(state.inverse_mass.iter().map(|&w| w > 0.0));
        if self.asleep.is_none() {
            self.asleep = world.try_query_filtered::<&SolverIndex, With<Sleeping>>();
        }
        if let Some(asleep) = &mut self.asleep {
            for index in asleep.iter(world) {
                if let Some(slot) = (*index).get().and_then(|i| free.get_mut(i)) {
                    *slot = true;
                }
            }
        }
    }
}

/// The free particles' speeds, sorted (a sleeping particle's is zero).
pub struct FreeSpeeds(Vec<f64>);

impl FreeSpeeds {
    /// The speeds of `world`'s free particles.
    pub fn of(world: &World) -> FreeSpeeds {
        let mut free = Vec::new();
        free_particles(world, &mut free);
        let state = world.resource::<ParticleState>();
        let mut speeds: Vec<f64> = (state.velocity.iter().zip(&free))
            .filter(|(_, f)| **f)
            .map(|(v, _)| v.length())
            .collect();
        speeds.sort_by(f64::total_cmp);
        FreeSpeeds(speeds)
    }

    /// The speed below which a share `q` of them lie (nearest rank); 0 with none.
    pub fn quantile(&self, q: f64) -> f64 {
        if self.0.is_empty() {
            return 0.0;
        }
        let rank = ((q * self.0.len() as f64).ceil() as usize).clamp(1, self.0.len());
        self.0[rank - 1]
    }
}
