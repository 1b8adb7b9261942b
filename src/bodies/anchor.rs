//! The component that hangs a particle on a rigid body.

use bevy::prelude::*;

/// Attach this particle to a rigid body (avian's or Rapier's) at `offset` in the body's frame. On a
/// dynamic body both ways: the body's weight hangs on the strand and the strand's pull
/// moves the body. On a static or kinematic body the particle follows it (and is made
/// [`Kinematic`](crate::world::particle::Kinematic)).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct BodyAnchor {
    /// The rigid body.
    pub body: Entity,
    /// Where on it, in the body's frame (about its origin, not its centre of mass).
    pub offset: Vec2,
}
