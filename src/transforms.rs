//! Transforms for the particles that want one, interpolated between ticks.
//!
//! The simulation's state is `f64` [`Position`]s; sprites, meshes and cameras read
//! `f32` [`Transform`]s. A particle with [`SyncTransform`] gets both: at the end of
//! every tick its position is recorded ([`TickPositions`]), and each frame, before
//! transform propagation, its translation is placed between the last two ticks'
//! positions by how far the fixed clock has run into the next tick — so motion is smooth
//! at any frame rate, one tick behind, as with avian's and Bevy's own interpolation.
//! Only `x` and `y` are written; `z` (the drawing order) and rotation and scale are the
//! user's.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::transform::TransformSystems;

use crate::schedule::{StrandsTick, TickSet};
use crate::world::particle::Position;

/// Keep this particle's [`Transform`] on its position.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
#[require(Transform, TickPositions)]
pub struct SyncTransform {
    /// Interpolate between the last two ticks by the fixed clock's overstep (for a
    /// simulation driven by a fixed schedule); `false` shows the latest tick as it is.
    pub interpolate: bool,
}

impl Default for SyncTransform {
    fn default() -> Self {
        Self { interpolate: true }
    }
}

/// A synced particle's position at the end of the last two ticks.
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[reflect(Component)]
pub struct TickPositions {
    /// At the end of the tick before the last.
    pub previous: DVec2,
    /// At the end of the last tick.
    pub current: DVec2,
    /// Whether a tick has been recorded (the first sets both).
    recorded: bool,
}

impl TickPositions {
    /// The position a fraction `alpha` (0 to 1) of the way from `previous` to `current`.
    pub fn at(&self, alpha: f64) -> DVec2 {
        self.previous.lerp(self.current, alpha.clamp(0.0, 1.0))
    }

    /// Whether a tick has ended since the particle got these (before, they are zero).
    pub fn is_recorded(&self) -> bool {
        self.recorded
    }
}

/// Records tick positions and writes transforms.
pub struct TransformSyncPlugin;

impl Plugin for TransformSyncPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<SyncTransform>()
            .register_type::<TickPositions>()
            .add_systems(StrandsTick, record_tick_positions.after(TickSet::Writeback))
            .add_systems(
                PostUpdate,
                write_transforms.before(TransformSystems::Propagate),
            );
    }
}

/// The end of a tick: the last position becomes the previous one.
fn record_tick_positions(mut particles: Query<(&Position, &mut TickPositions)>) {
    for (position, mut ticks) in &mut particles {
        let previous = if ticks.recorded {
            ticks.current
        } else {
            position.0
        };
        let new = TickPositions {
            previous,
            current: position.0,
            recorded: true,
        };
        ticks.set_if_neq(new);
    }
}

/// Each frame: every synced particle's translation, between its last two ticks.
fn write_transforms(
    fixed: Option<Res<Time<Fixed>>>,
    mut particles: Query<(&SyncTransform, &TickPositions, &Position, &mut Transform)>,
) {
    let overstep = fixed.map_or(1.0, |t| t.overstep_fraction_f64());
    for (sync, ticks, position, mut transform) in &mut particles {
        let alpha = if sync.interpolate { overstep } else { 1.0 };
        // Before its first tick a particle shows where it was spawned.
        let at = if ticks.is_recorded() {
            ticks.at(alpha)
        } else {
            position.0
        };
        let at = at.as_vec2();
        if transform.translation.truncate() != at {
            transform.translation.x = at.x;
            transform.translation.y = at.y;
        }
    }
}
