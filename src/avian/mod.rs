//! Strands in an avian2d world (feature `avian`): avian's adapter to the engine-neutral
//! coupling in [`bodies`](crate::bodies).
//!
//! - A collider marked [`CollidesWithStrands`] gets an outline strand; on a dynamic
//!   body a frame carrying the body's mass, and what strands push on it goes back to
//!   the body.
//! - A particle with a [`BodyAnchor`] hangs on a body, both ways.
//! - Gravity is avian's ([`Gravity`]) unless [`StrandsAvianPlugin::share_gravity`] is
//!   off.
//!
//! Avian works in `f32`, the strands in `f64`: values are converted at this boundary
//! only. A tick of the strands runs after avian's step in the same schedule: a body
//! the strands hand over gets its pose and velocity written back for avian's next
//! step; the others' impulses reach them as forces over that step.
//!
//! Imports: [`crate::bodies`], [`crate::world`], [`crate::schedule`], and avian2d.

use bevy::math::Rot2;
use bevy::prelude::*;

use avian2d::prelude::{
    AngularVelocity, Collider, ColliderOf, ComputedAngularInertia, ComputedCenterOfMass,
    ComputedMass, Forces, Gravity, LinearVelocity, PhysicsLengthUnit, PhysicsSystems, Position,
    RigidBody, Rotation, Sleeping, WriteRigidBodyForces,
};

use crate::bodies::shapes::shape_outline;
pub use crate::bodies::{BodyAnchor, BodyCoupling, CollidesWithStrands};
use crate::bodies::{
    BodyHeld, BodyMotion, BodyOutline, BodyPush, BodySync, BodyView, MarkedCollider, OutlinedFrom,
    outline_collider, spawn_state,
};
use crate::schedule::{StrandsSystems, StrandsTick};
use crate::world::config::{CollisionConfig, LengthUnit, StrandsConfig};

/// Couples the strands with avian2d. Add it after [`StrandsPlugin`](crate::StrandsPlugin)
/// and avian's `PhysicsPlugins`.
#[derive(Clone, Copy, Debug)]
pub struct StrandsAvianPlugin {
    /// Use avian's [`Gravity`] for the strands, every tick.
    pub share_gravity: bool,
}

impl Default for StrandsAvianPlugin {
    fn default() -> Self {
        Self {
            share_gravity: true,
        }
    }
}

impl Plugin for StrandsAvianPlugin {
    fn build(&self, app: &mut App) {
        crate::bodies::add_adapter::<RigidBody, Collider, _, _, _>(
            app,
            mirror_bodies,
            build_outlines,
            (hand_over, push_bodies).chain(),
        );
        app.register_required_components::<RigidBody, HeldUp>();
        // The strands start from the bodies' new state, whatever schedule drives
        // both (avian's default and the strands' are `FixedPostUpdate`).
        app.configure_sets(
            FixedPostUpdate,
            StrandsSystems.after(PhysicsSystems::Writeback),
        )
        .add_systems(PostStartup, check_length_unit)
        .add_observer(take_spawn_state);
        if self.share_gravity {
            // Before the bodies are followed: their hand-over reads the gravity.
            app.add_systems(StrandsTick, share_gravity.in_set(BodySync::Read));
        }
    }
}

/// The strands fall as the bodies do.
fn share_gravity(gravity: Option<Res<Gravity>>, mut config: ResMut<StrandsConfig>) {
    if let Some(gravity) = gravity {
        let g = gravity.0.as_dvec2();
        if g.is_finite() && config.gravity != g {
            config.gravity = g;
        }
    }
}

/// A world whose two engines measure length differently collides at the wrong
/// thickness: say so once, at the start.
fn check_length_unit(avian: Option<Res<PhysicsLengthUnit>>, ours: Option<Res<LengthUnit>>) {
    let (Some(avian), Some(ours)) = (avian, ours) else {
        return;
    };
    if !crate::bodies::same_length_unit(avian.0 as f64, ours.0) {
        warn!(
            "bevy_strands: avian's PhysicsLengthUnit is {} but the strands' LengthUnit is {}: \
             use StrandsPlugin::with_length_unit({})",
            avian.0, ours.0, avian.0
        );
    }
}

/// A new body's state at its spawn, for the strands' first tick.
fn take_spawn_state(
    added: On<Add<BodyHeld>>,
    mut bodies: Query<(
        &Transform,
        Option<&LinearVelocity>,
        Option<&AngularVelocity>,
        &mut BodyHeld,
    )>,
) {
    if let Ok((transform, linear, angular, mut held)) = bodies.get_mut(added.entity) {
        let linear = linear.map_or(Vec2::ZERO, |v| v.0);
        let angular = angular.map_or(0.0, |w| w.0);
        *held = spawn_state(transform, linear, angular);
    }
}

/// Avian's rotation as an angle (avian's sine and cosine drift off the unit circle by
/// rounding, which `Rot2::from_sin_cos` refuses).
fn planar(rotation: &Rotation) -> Rot2 {
    Rot2::radians(rotation.sin.atan2(rotation.cos))
}

/// What the coupling mirrors of an avian body.
type AvianBody = (
    &'static Position,
    &'static Rotation,
    &'static LinearVelocity,
    &'static AngularVelocity,
    &'static RigidBody,
    &'static ComputedMass,
    &'static ComputedAngularInertia,
    &'static ComputedCenterOfMass,
    Has<Sleeping>,
    &'static mut BodyView,
);

/// Each avian body's pose, velocity and mass properties into its [`BodyView`].
fn mirror_bodies(mut bodies: Query<AvianBody>) {
    for (position, rotation, linear, angular, body, mass, inertia, centre, asleep, mut view) in
        &mut bodies
    {
        let motion = match body {
            RigidBody::Dynamic => BodyMotion::Dynamic,
            RigidBody::Kinematic => BodyMotion::Kinematic,
            RigidBody::Static => BodyMotion::Static,
        };
        view.set_if_neq(BodyView {
            position: position.0,
            rotation: planar(rotation),
            linear: linear.0,
            angular: angular.0,
            motion,
            mass: mass.value(),
            inertia: inertia.value(),
            centre_of_mass: centre.0,
            sleeping: asleep,
        });
    }
}

/// The outline of each newly marked avian collider.
#[allow(clippy::type_complexity)]
fn build_outlines(
    mut commands: Commands,
    colliders: Query<
        (
            Entity,
            &Collider,
            &CollidesWithStrands,
            Option<&ColliderOf>,
            Option<&Position>,
            Option<&Rotation>,
            &GlobalTransform,
        ),
        Without<BodyOutline>,
    >,
    bodies: Query<(&BodyView, &BodyHeld)>,
    config: Res<StrandsConfig>,
    collisions: Res<CollisionConfig>,
) {
    let tick = config.tick_seconds();
    for (entity, collider, marker, of, position, rotation, transform) in &colliders {
        commands
            .entity(entity)
            .insert(OutlinedFrom::<Collider>::default());
        let outline = shape_outline(collider.shape_scaled().as_typed_shape(), marker.tolerance);
        let body_entity = of.map_or(entity, |of| of.body);
        let body = bodies.get(body_entity).ok().map(|(body, held)| {
            // The collider's own pose where avian keeps one (a child collider), else
            // the body's.
            let (at, turn) = match (position, rotation) {
                (Some(p), Some(r)) => (body.local_point(p.0), body.rotation.inverse() * planar(r)),
                _ => (Vec2::ZERO, Rot2::IDENTITY),
            };
            let (start, _) = body.at_tick_start(held, tick, collisions.thickness);
            (body_entity, start, at, turn)
        });
        outline_collider(
            &mut commands,
            MarkedCollider {
                entity,
                outline,
                body: body.as_ref().map(|(e, v, at, turn)| (*e, v, *at, *turn)),
                transform,
                marker: *marker,
            },
        );
    }
}

/// The states the strands hand over, written into the bodies avian steps next.
fn hand_over(
    mut bodies: Query<(
        &mut BodyPush,
        &mut Position,
        &mut Rotation,
        &mut LinearVelocity,
        &mut AngularVelocity,
    )>,
) {
    for (mut push, mut position, mut rotation, mut linear, mut angular) in &mut bodies {
        let Some(state) = push.state.take() else {
            continue;
        };
        position.set_if_neq(Position(state.position));
        rotation.set_if_neq(Rotation::radians(state.rotation.as_radians()));
        linear.set_if_neq(LinearVelocity(state.linear));
        angular.set_if_neq(AngularVelocity(state.angular));
    }
}

/// What the strands last held a settled body up with, for the step after they wake
/// it: asleep, its frame holds still and takes no push, and without this it would
/// fall for that step before they hold it again.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct HeldUp {
    /// The force.
    pub force: Vec2,
    /// The torque.
    pub torque: f32,
}

/// The strands' pushes as forces over avian's next step: without waking the body when
/// the strands under it have settled (so avian may put it to sleep), and waking it,
/// held up as it was, when one that has not touches it asleep.
fn push_bodies(
    mut commands: Commands,
    mut bodies: Query<(Entity, &mut BodyPush, &mut HeldUp, Forces)>,
) {
    for (entity, mut push, mut held, mut forces) in &mut bodies {
        if *push == BodyPush::default() {
            continue;
        }
        let BodyPush {
            mut force,
            mut torque,
            settled,
            wake,
            ..
        } = std::mem::take(&mut *push);
        if wake {
            // Removing the marker wakes the body's island; asleep, it took no push.
            commands.entity(entity).try_remove::<Sleeping>();
            (force, torque) = (held.force, held.torque);
        } else if settled && (force, torque) != (Vec2::ZERO, 0.0) {
            held.set_if_neq(HeldUp { force, torque });
        }
        if settled {
            let mut forces = forces.non_waking();
            forces.apply_force(force);
            forces.apply_torque(torque);
        } else {
            forces.apply_force(force);
            forces.apply_torque(torque);
        }
    }
}
