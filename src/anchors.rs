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
///
/// ```
/// use bevy::math::DVec2;
/// use bevy::prelude::*;
/// use bevy_strands::prelude::*;
///
/// let mut app = App::new();
/// app.add_plugins((MinimalPlugins, StrandsPlugin::manual()));
/// app.finish();
/// app.cleanup();
/// // A crane's hook, 10 cm below the crane's origin.
/// let at = Vec3::new(0.3, 1.0, 0.0);
/// let crane = app
///     .world_mut()
///     .spawn((Transform::from_translation(at), GlobalTransform::from_translation(at)))
///     .id();
/// let rope = StrandBuilder::line(DVec2::new(0.3, 0.9), DVec2::NEG_Y, 8, 0.05)
///     .spawn_in(app.world_mut())
///     .unwrap();
/// let hook = app.world().get::<Strand>(rope).unwrap().particles[0];
/// app.world_mut().entity_mut(hook).insert(Anchor {
///     target: crane,
///     offset: Vec2::new(0.0, -0.1),
/// });
/// app.world_mut().run_schedule(StrandsTick);
/// // The rope hangs from the hook instead of falling (transforms are f32).
/// let hook_at = app.world().get::<Position>(hook).unwrap().0;
/// assert!(hook_at.distance(DVec2::new(0.3, 0.9)) < 1e-6);
/// ```
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
