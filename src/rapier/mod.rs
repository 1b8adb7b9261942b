//! Strands in a bevy_rapier2d world (feature `rapier`): Rapier's adapter to the
//! engine-neutral coupling in [`bodies`](crate::bodies), at parity with avian's.
//!
//! - A collider marked [`CollidesWithStrands`] gets an outline strand; on a dynamic
//!   body a frame carrying the body's mass, and what strands push on it goes back to
//!   the body.
//! - A particle with a [`BodyAnchor`] hangs on a body, both ways.
//! - Gravity is Rapier's (the default context's [`RapierConfiguration`]) unless
//!   [`StrandsRapierPlugin::share_gravity`] is off.
//!
//! Run Rapier in the fixed schedule (`RapierPhysicsPlugin::default().in_fixed_schedule()`,
//! or `in_schedule(FixedPostUpdate)`): the strands' tick then follows Rapier's step; a
//! body the strands hand over gets its `Transform` and `Velocity` written back for
//! Rapier's next step, the others' pushes act over it as an [`ExternalForce`] (added
//! to whatever force the game sets, and taken off again a tick later). Bodies
//! are read from their `Transform`, so a coupled body sits at the root of its
//! hierarchy, as Rapier's own bodies normally do; a collider may be the body's child.
//!
//! Imports: [`crate::bodies`], [`crate::world`], [`crate::schedule`], and bevy_rapier2d.

use bevy::math::Rot2;
use bevy::prelude::*;

use bevy_rapier2d::plugin::context::RapierRigidBodySet;
use bevy_rapier2d::plugin::{PhysicsSet, RapierContextEntityLink};
use bevy_rapier2d::prelude::{
    Collider, ExternalForce, LockedAxes, RapierConfiguration, RapierContextSimulation,
    RapierRigidBodyHandle, ReadMassProperties, RigidBody, Sleeping, Velocity,
};

use crate::bodies::shapes::shape_outline;
pub use crate::bodies::{BodyAnchor, BodyCoupling, CollidesWithStrands};
use crate::bodies::{
    BodyHeld, BodyMotion, BodyOutline, BodyPush, BodySync, BodyView, MarkedCollider, OutlinedFrom,
    outline_collider, planar_rotation, spawn_state,
};
use crate::schedule::{StrandsSystems, StrandsTick};
use crate::world::config::{CollisionConfig, LengthUnit, StrandsConfig};

/// Couples the strands with bevy_rapier2d. Add it after
/// [`StrandsPlugin`](crate::StrandsPlugin) and `RapierPhysicsPlugin`.
#[derive(Clone, Copy, Debug)]
pub struct StrandsRapierPlugin {
    /// Use Rapier's gravity for the strands, every tick.
    pub share_gravity: bool,
}

impl Default for StrandsRapierPlugin {
    fn default() -> Self {
        Self {
            share_gravity: true,
        }
    }
}

impl Plugin for StrandsRapierPlugin {
    fn build(&self, app: &mut App) {
        crate::bodies::add_adapter::<RigidBody, Collider, _, _, _>(
            app,
            mirror_bodies,
            build_outlines,
            (hand_over, push_bodies).chain(),
        );
        // Rapier writes a body's velocity back only where it has a Velocity, and the
        // strands' force goes through an ExternalForce.
        // The body's sleep is read and written through this (Rapier adds none).
        app.register_required_components::<RigidBody, Velocity>()
            .register_required_components::<RigidBody, Sleeping>()
            .register_required_components::<RigidBody, ExternalForce>()
            .register_required_components::<RigidBody, PushedForce>()
            // Rapier stepped in `FixedPostUpdate` goes first too.
            .configure_sets(FixedPostUpdate, StrandsSystems.after(PhysicsSet::Writeback))
            .add_systems(PostStartup, check_length_unit)
            .add_observer(take_spawn_state);
        if self.share_gravity {
            // Before the bodies are followed: their hand-over reads the gravity.
            app.add_systems(StrandsTick, share_gravity.in_set(BodySync::Read));
        }
    }
}

/// The strands fall as the bodies do (the first Rapier context's gravity).
fn share_gravity(contexts: Query<&RapierConfiguration>, mut config: ResMut<StrandsConfig>) {
    if let Some(rapier) = contexts.iter().next() {
        let g = rapier.gravity.as_dvec2();
        if g.is_finite() && config.gravity != g {
            config.gravity = g;
        }
    }
}

/// A world whose two engines measure length differently collides at the wrong
/// thickness: say so once, at the start.
fn check_length_unit(contexts: Query<&RapierContextSimulation>, ours: Option<Res<LengthUnit>>) {
    let (Some(rapier), Some(ours)) = (contexts.iter().next(), ours) else {
        return;
    };
    let unit = rapier.integration_parameters.length_unit;
    if !crate::bodies::same_length_unit(unit as f64, ours.0) {
        warn!(
            "bevy_strands: Rapier's length unit is {unit} but the strands' LengthUnit is {}: \
             use StrandsPlugin::with_length_unit({unit})",
            ours.0
        );
    }
}

/// A new body's state at its spawn, for the strands' first tick.
fn take_spawn_state(
    added: On<Add<BodyHeld>>,
    mut bodies: Query<(&Transform, Option<&Velocity>, &mut BodyHeld)>,
) {
    if let Ok((transform, velocity, mut held)) = bodies.get_mut(added.entity) {
        let velocity = velocity.copied().unwrap_or_default();
        *held = spawn_state(transform, velocity.linear, velocity.angular);
    }
}

/// What the coupling mirrors of a Rapier body.
type RapierBody = (
    &'static Transform,
    &'static Velocity,
    &'static RigidBody,
    &'static ReadMassProperties,
    Option<&'static LockedAxes>,
    Option<&'static Sleeping>,
    &'static mut BodyView,
);

/// Each Rapier body's pose, velocity and mass properties into its [`BodyView`].
fn mirror_bodies(mut bodies: Query<RapierBody>) {
    for (transform, velocity, body, mass, locked, sleeping, mut view) in &mut bodies {
        let motion = match body {
            RigidBody::Dynamic => BodyMotion::Dynamic,
            RigidBody::KinematicPositionBased | RigidBody::KinematicVelocityBased => {
                BodyMotion::Kinematic
            }
            RigidBody::Fixed => BodyMotion::Static,
        };
        let rotation_locked = locked.is_some_and(|l| l.contains(LockedAxes::ROTATION_LOCKED));
        let inertia = if rotation_locked {
            f32::INFINITY
        } else {
            mass.principal_inertia
        };
        view.set_if_neq(BodyView {
            position: transform.translation.truncate(),
            rotation: planar_rotation(transform.rotation),
            linear: velocity.linear,
            angular: velocity.angular,
            motion,
            mass: mass.mass,
            inertia,
            centre_of_mass: mass.local_center_of_mass,
            sleeping: sleeping.is_some_and(|s| s.sleeping),
        });
    }
}

/// The outline of each newly marked Rapier collider: on its own body, or on the body of
/// the nearest ancestor that has one (its pose composed from the transforms between).
#[allow(clippy::type_complexity)]
fn build_outlines(
    mut commands: Commands,
    colliders: Query<
        (Entity, &Collider, &CollidesWithStrands, &GlobalTransform),
        Without<BodyOutline>,
    >,
    bodies: Query<(&BodyView, &BodyHeld)>,
    parents: Query<(&ChildOf, &Transform)>,
    config: Res<StrandsConfig>,
    collisions: Res<CollisionConfig>,
) {
    let tick = config.tick_seconds();
    for (entity, collider, marker, transform) in &colliders {
        commands
            .entity(entity)
            .insert(OutlinedFrom::<Collider>::default());
        let outline = shape_outline(collider.raw.as_typed_shape(), marker.tolerance);
        // Walk up to the body, composing the collider's pose in its frame.
        let (mut at, mut turn, mut on) = (Vec2::ZERO, Rot2::IDENTITY, entity);
        let mut body = None;
        for _ in 0..16 {
            if let Ok((view, held)) = bodies.get(on) {
                let (view, _) = view.at_tick_start(held, tick, collisions.thickness);
                body = Some((on, view, at, turn));
                break;
            }
            let Ok((parent, local)) = parents.get(on) else {
                break;
            };
            let local_turn = planar_rotation(local.rotation);
            at = local.translation.truncate() + local_turn * at;
            turn = local_turn * turn;
            on = parent.parent();
        }
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

/// The part of a body's [`ExternalForce`] that the strands put there last tick.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct PushedForce {
    /// The force.
    pub force: Vec2,
    /// The torque.
    pub torque: f32,
}

/// The states the strands hand over, written into the bodies Rapier steps next.
fn hand_over(mut bodies: Query<(&mut BodyPush, &mut Transform, &mut Velocity)>) {
    for (mut push, mut transform, mut velocity) in &mut bodies {
        let Some(state) = push.state.take() else {
            continue;
        };
        let at = state.position.extend(transform.translation.z);
        let turn = Quat::from_rotation_z(state.rotation.as_radians());
        if transform.translation != at || transform.rotation != turn {
            transform.translation = at;
            transform.rotation = turn;
        }
        velocity.set_if_neq(Velocity {
            linear: state.linear,
            angular: state.angular,
        });
    }
}

/// What the rapier adapter writes a push into: the body's [`ExternalForce`], its
/// record of the strands' part of it, its [`Sleeping`], and its handle into Rapier's
/// set (for a change that must not wake it).
type PushedBody = (
    &'static mut BodyPush,
    &'static mut PushedForce,
    &'static mut ExternalForce,
    Option<&'static mut Sleeping>,
    Option<&'static RapierRigidBodyHandle>,
    Option<&'static RapierContextEntityLink>,
);

/// The strands' pushes into each body's [`ExternalForce`] for Rapier's next step, in
/// place of last tick's (Rapier keeps an external force until it is changed). A
/// change of the component wakes the body, so while the strands under it have
/// settled the force goes straight into Rapier's body without waking it (Rapier may
/// put it to sleep, and wakes it with the force it rests on); one that has not
/// settled touching it asleep wakes it.
fn push_bodies(mut bodies: Query<PushedBody>, mut sets: Query<&mut RapierRigidBodySet>) {
    for (mut push, mut pushed, mut external, sleeping, handle, link) in &mut bodies {
        let new = std::mem::take(&mut *push);
        let asleep = sleeping.as_ref().is_some_and(|s| s.sleeping);
        if new.wake
            && let Some(mut sleeping) = sleeping.filter(|_| asleep)
        {
            sleeping.sleeping = false;
        }
        // Asleep, its frame holds still and takes no push: the force it rests on
        // stays, for the step it wakes in (this one, when woken now).
        if asleep {
            continue;
        }
        if (new.force, new.torque) == (Vec2::ZERO, 0.0) && *pushed == PushedForce::default() {
            continue;
        }
        let force = external.force + new.force - pushed.force;
        let torque = external.torque + new.torque - pushed.torque;
        *pushed = PushedForce {
            force: new.force,
            torque: new.torque,
        };
        // Settled, straight into Rapier's body, unseen by the change detection that
        // would wake it.
        if new.settled
            && let Some((handle, link)) = handle.zip(link)
            && let Ok(mut set) = sets.get_mut(link.0)
            && let Some(body) = set.bodies.get_mut(handle.0)
        {
            body.reset_forces(false);
            body.reset_torques(false);
            body.add_force(force, false);
            body.add_torque(torque, false);
            let external = external.bypass_change_detection();
            (external.force, external.torque) = (force, torque);
        } else {
            (external.force, external.torque) = (force, torque);
        }
    }
}
