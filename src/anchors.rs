//! Anchors: a particle attached to any entity's `GlobalTransform` at a local offset —
//! a rope tied to a crane, a hair root on a moving sprite. An anchored particle is
//! [`Kinematic`]: each tick it is given the velocity that brings it, at the tick's end,
//! exactly to the anchor point, so the strand follows the entity and everything it
//! pushes feels a body of infinite mass.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::schedule::{StrandsTick, TickSet};
use crate::world::config::StrandsConfig;
use crate::world::particle::{Kinematic, Position, Velocity};
use crate::world::problems::InputProblems;

/// Attach this particle to `target`'s `GlobalTransform`, at `offset` in the target's
/// own frame (rotated and scaled with it).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
#[require(Kinematic)]
pub struct Anchor {
    /// The entity followed.
    pub target: Entity,
    /// Where on it, in its local frame.
    pub offset: Vec2,
}

/// Drives anchored particles.
pub struct AnchorPlugin;

impl Plugin for AnchorPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<Anchor>()
            .add_systems(StrandsTick, follow_anchors.in_set(TickSet::Prepare));
    }
}

/// Each anchored particle's velocity for the tick: from where it is to its anchor point.
fn follow_anchors(
    config: Res<StrandsConfig>,
    targets: Query<&GlobalTransform>,
    mut particles: Query<(Entity, &Anchor, &Position, &mut Velocity)>,
    mut problems: ResMut<InputProblems>,
) {
    let tick = config.tick_seconds();
    if !(tick.is_finite() && tick > 0.0) {
        return;
    }
    for (entity, anchor, position, mut velocity) in &mut particles {
        let Ok(target) = targets.get(anchor.target) else {
            problems.report(
                entity,
                format!(
                    "anchor target {} has no GlobalTransform: held still",
                    anchor.target
                ),
            );
            velocity.set_if_neq(Velocity(DVec2::ZERO));
            continue;
        };
        let point = target
            .transform_point(anchor.offset.extend(0.0))
            .truncate()
            .as_dvec2();
        velocity.set_if_neq(Velocity((point - position.0) / tick));
    }
}
