//! The engine-neutral picture of a rigid body: what the coupling reads of a body each
//! tick ([`BodyView`]) and what it gives back ([`BodyPush`]). Each engine's adapter
//! fills the first from its own components before the strands' tick and hands the
//! second to its own force API after it; nothing else of the coupling knows the
//! engine.

use bevy::math::{DVec2, Rot2};
use bevy::prelude::*;

use super::handoff::BodyState;

/// How a body moves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Reflect)]
pub enum BodyMotion {
    /// Moved by forces, contacts and joints: coupled both ways.
    #[default]
    Dynamic,
    /// Moved only by its own velocity or pose: it drives what hangs on it.
    Kinematic,
    /// Never moves.
    Static,
}

/// A rigid body as the strands see it, mirrored from the physics engine at the start
/// of each strands tick (in the engine's `f32`). Added to every rigid body of a
/// coupled engine; read-only to users.
#[derive(Component, Clone, Copy, Debug, PartialEq, Reflect)]
#[reflect(Component)]
pub struct BodyView {
    /// The body's origin in the world.
    pub position: Vec2,
    /// Its orientation.
    pub rotation: Rot2,
    /// The velocity of its centre of mass.
    pub linear: Vec2,
    /// Its angular velocity, radians per second, counter-clockwise.
    pub angular: f32,
    /// How it moves.
    pub motion: BodyMotion,
    /// Its mass (0 until the engine has computed it).
    pub mass: f32,
    /// Its angular inertia about the centre of mass (infinite with rotation locked).
    pub inertia: f32,
    /// Its centre of mass in its own frame.
    pub centre_of_mass: Vec2,
    /// Whether the engine has put it to sleep.
    pub sleeping: bool,
}

impl Default for BodyView {
    fn default() -> Self {
        Self {
            position: Vec2::ZERO,
            rotation: Rot2::IDENTITY,
            linear: Vec2::ZERO,
            angular: 0.0,
            motion: BodyMotion::Static,
            mass: 0.0,
            inertia: 0.0,
            centre_of_mass: Vec2::ZERO,
            sleeping: false,
        }
    }
}

impl BodyView {
    /// Whether forces move it.
    pub fn is_dynamic(&self) -> bool {
        self.motion == BodyMotion::Dynamic
    }

    /// The world point of `offset` (in the body's frame, about its origin).
    pub fn world_point(&self, offset: Vec2) -> Vec2 {
        self.position + self.rotation * offset
    }

    /// The point of the body's frame at world point `point`.
    pub fn local_point(&self, point: Vec2) -> Vec2 {
        self.rotation.inverse() * (point - self.position)
    }

    /// The world point of `offset`, its velocity, and its arm from the centre of mass.
    pub fn point_motion(&self, offset: Vec2) -> (DVec2, DVec2, Vec2) {
        let point = self.world_point(offset);
        let arm = point - self.world_point(self.centre_of_mass);
        let velocity = self.linear + self.angular * arm.perp();
        (point.as_dvec2(), velocity.as_dvec2(), arm)
    }

    /// The body where the strands' tick takes it up: as the strands (or its spawn) last
    /// handed it to the engine, when the engine has only stepped it since — its centre
    /// of mass within `tolerance` of where that state and the engine's velocity take it
    /// over `tick` — with whether it was; else where the engine has it.
    pub fn at_tick_start(&self, held: &BodyHeld, tick: f64, tolerance: f64) -> (BodyView, bool) {
        let Some(h) = held.0 else {
            return (*self, false);
        };
        let centre = self.world_point(self.centre_of_mass).as_dvec2();
        let held_centre = (h.position + h.rotation * self.centre_of_mass).as_dvec2();
        let expected = held_centre + 0.5 * tick * (h.linear + self.linear).as_dvec2();
        // Not within tolerance, NaN included.
        let stepped = (centre - expected).length() <= tolerance;
        if !stepped {
            return (*self, false);
        }
        let view = BodyView {
            position: h.position,
            rotation: h.rotation,
            linear: h.linear,
            angular: h.angular,
            ..*self
        };
        (view, true)
    }

    /// Whether the engine has given it usable mass properties.
    pub fn has_mass(&self) -> bool {
        self.mass.is_finite() && self.mass > 0.0 && self.inertia > 0.0
    }
}

/// What the strands give a body at the tick's end, handed to the engine by its
/// adapter: the state a body with a frame ends the tick in (the engine steps it from
/// there), and a force and a torque about its centre of mass to act through the
/// engine's next step (what lone anchors, with no frame, pulled).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyPush {
    /// The body's pose and velocity to write into the engine.
    pub state: Option<BodyState>,
    /// The force, world frame.
    pub force: Vec2,
    /// The torque.
    pub torque: f32,
    /// Every strand that touches or holds it has settled (rested the sleep time, or
    /// sleeps): the push must not wake it, so that its engine may put it to sleep.
    pub settled: bool,
    /// Its engine has it asleep and a strand that has not settled touches or holds
    /// it: wake it.
    pub wake: bool,
}

/// The state the strands last wrote into a body (the start of the engine's step that
/// followed); `None` while the strands do not integrate it.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyHeld(pub Option<BodyState>);

/// The angle of a rotation about the z axis.
pub fn planar_rotation(rotation: Quat) -> Rot2 {
    Rot2::radians(2.0 * rotation.z.atan2(rotation.w))
}

/// A body's state at its spawn, from its transform and the engine's velocity: where the
/// strands take it up on its first tick (the engine steps it before they see it).
pub fn spawn_state(transform: &Transform, linear: Vec2, angular: f32) -> BodyHeld {
    BodyHeld(Some(BodyState {
        position: transform.translation.truncate(),
        rotation: planar_rotation(transform.rotation),
        linear,
        angular,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_turning_body_moves_a_point_across_its_arm() {
        let body = BodyView {
            position: Vec2::new(1.0, 0.0),
            rotation: Rot2::degrees(90.0),
            linear: Vec2::new(0.0, 1.0),
            angular: 2.0,
            motion: BodyMotion::Dynamic,
            mass: 1.0,
            inertia: 1.0,
            ..default()
        };
        let (point, velocity, arm) = body.point_motion(Vec2::X);
        assert!((point - DVec2::new(1.0, 1.0)).length() < 1e-6);
        assert!((arm - Vec2::Y).length() < 1e-6);
        // ω × r = 2 (−1, 0), plus the centre's velocity.
        assert!((velocity - DVec2::new(-2.0, 1.0)).length() < 1e-6);
        assert!(
            (body.local_point(body.world_point(Vec2::new(0.3, -0.2))) - Vec2::new(0.3, -0.2))
                .length()
                < 1e-6
        );
    }
}
