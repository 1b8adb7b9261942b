//! A winch: a strand whose first edge changes length at a given speed, paying rope out
//! or reeling it in at its first particle (usually pinned or anchored). When the first
//! edge grows past one and a half spacings a particle is inserted on it; when it shrinks
//! below half a spacing its far particle is taken out and the edge joins the next one.
//! The constraint solve meets the new rest lengths every step, so the rope stays exact
//! while its length changes.

use bevy::prelude::*;

use crate::schedule::{StrandsTick, TickSet};
use crate::world::config::StrandsConfig;
use crate::world::particle::{Mass, Particle, Position, Velocity};
use crate::world::strand::{Strand, StrandOf};

/// Change this strand's length at its first particle.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct Winch {
    /// Metres a second: positive pays rope out, negative reels it in.
    pub speed: f64,
    /// The rest spacing of the particles it adds.
    pub spacing: f64,
    /// The shortest the strand may get (it stops reeling there).
    pub min_length: f64,
    /// The longest the strand may get (it stops paying out there).
    pub max_length: f64,
}

/// Drives winches.
pub struct WinchPlugin;

impl Plugin for WinchPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<Winch>()
            .add_systems(StrandsTick, run_winches.in_set(TickSet::Prepare));
    }
}

fn run_winches(
    mut commands: Commands,
    config: Res<StrandsConfig>,
    mut strands: Query<(Entity, &Winch, &mut Strand)>,
    particles: Query<(&Position, &Velocity, &Mass)>,
) {
    let tick = config.tick_seconds();
    for (entity, winch, mut strand) in &mut strands {
        if strand.closed
            || strand.particles.len() < 2
            || winch.spacing.is_nan()
            || winch.spacing <= 0.0
        {
            continue;
        }
        let length: f64 = strand.rest_lengths.iter().sum();
        let change =
            (winch.speed * tick).clamp(winch.min_length - length, winch.max_length - length);
        if change == 0.0 || !change.is_finite() {
            continue;
        }
        let first = strand.rest_lengths[0] + change;
        if first > 1.5 * winch.spacing {
            // Pay out: a particle on the first edge, one spacing from its far end.
            let (Ok(a), Ok(b)) = (
                particles.get(strand.particles[0]),
                particles.get(strand.particles[1]),
            ) else {
                continue;
            };
            let t = (first - winch.spacing) / first;
            let new = commands
                .spawn((
                    Particle,
                    Position(a.0.0.lerp(b.0.0, t)),
                    Velocity(a.1.0.lerp(b.1.0, t)),
                    *b.2,
                    StrandOf(entity),
                ))
                .id();
            strand.particles.insert(1, new);
            strand.rest_lengths[0] = winch.spacing;
            strand.rest_lengths.insert(0, first - winch.spacing);
            if !strand.rest_angles.is_empty() {
                strand.rest_angles.insert(0, 0.0);
            }
        } else if first < 0.5 * winch.spacing && strand.particles.len() > 2 {
            // Reel in: the first edge's far particle goes; the edge takes the next one's length.
            let gone = strand.particles.remove(1);
            let next = strand.rest_lengths.remove(1);
            strand.rest_lengths[0] = first + next;
            if !strand.rest_angles.is_empty() {
                strand.rest_angles.remove(0);
            }
            commands.entity(gone).despawn();
        } else if first > 0.0 {
            strand.rest_lengths[0] = first;
        }
    }
}

/// Rope length of a strand (the sum of its rest lengths).
pub fn rope_length(strand: &Strand) -> f64 {
    strand.rest_lengths.iter().sum()
}
