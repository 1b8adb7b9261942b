//! Strands in an avian2d world (feature `avian`; avian's default `f32` build).
//!
//! - A collider marked [`CollidesWithStrands`] gets an outline strand, as the crate's
//!   own [`StrandCollider`](crate::colliders::StrandCollider)s do: strands meet it
//!   through the same continuous detection, impulses and fail-safe. On a dynamic body
//!   the outline's vertices carry the body's mass, and what strands push on them goes
//!   back to the body ([`coupling`]).
//! - A particle with a [`BodyAnchor`] hangs on a body: a crate on a rope pulls the rope
//!   down and the rope holds it up, with every edge exact.
//! - Gravity is avian's ([`Gravity`]) unless [`StrandsAvianPlugin::share_gravity`] is
//!   off.
//!
//! Avian works in `f32`, the strands in `f64`: values are converted at this boundary
//! only. A tick of the strands runs after avian's step in the same schedule, starting
//! from the bodies' new poses and velocities; the impulses it measures reach the bodies
//! before avian's next step.

pub mod anchor;
pub mod coupling;
pub mod shapes;
pub mod truss;

use bevy::prelude::*;

use avian2d::prelude::{
    Collider, ComputedCenterOfMass, Gravity, PhysicsSystems, RigidBody, Rotation,
};

use crate::colliders::{
    ColliderShape, OutlineBuild, StrandCollider, spawn_anchored_outline, spawn_outline,
};
use crate::rollback::{RollbackApp, StepRollback};
use crate::schedule::{
    CollideSet, ConstrainSet, StepSet, StrandsStep, StrandsSystems, StrandsTick, TickSet,
};
use crate::world::config::StrandsConfig;
use crate::world::particle::Kinematic;
pub use anchor::BodyAnchor;
pub use coupling::BodyCoupling;
use truss::{OutlineVertex, spawn_truss};

/// Make strands collide with this avian collider, its curves drawn within `tolerance`.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct CollidesWithStrands {
    /// How far the outline's polygon may stand off a curve.
    pub tolerance: f32,
}

impl Default for CollidesWithStrands {
    fn default() -> Self {
        Self { tolerance: 1e-3 }
    }
}

/// On a collider whose outline this module built (or refused to build).
#[derive(Component, Clone, Copy, Debug, Default)]
struct AvianOutline;

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
        // No step that couples a body is taken again in halves: avian moves its bodies
        // between ticks, so an anchored end starts the tick off its length by what
        // avian moved it, and half the step corrects that twice as fast (a rope of a
        // two-thousandth of its crate flew apart).
        app.init_resource::<StepRollback>();
        app.world_mut()
            .resource_mut::<StepRollback>()
            .forbid_when(|world| {
                world
                    .get_resource::<BodyCoupling>()
                    .is_some_and(BodyCoupling::couples)
            });
        app.register_type::<CollidesWithStrands>()
            .register_type::<BodyAnchor>()
            .init_resource::<BodyCoupling>()
            // The strands start from the bodies' new state, whatever schedule drives
            // both (avian's default and the strands' are `FixedPostUpdate`).
            .configure_sets(
                FixedPostUpdate,
                StrandsSystems.after(PhysicsSystems::Writeback),
            )
            .add_systems(
                StrandsTick,
                (
                    // Before the bodies are followed, so that new ties start taut.
                    (drop_unmarked, build_body_outlines, truss::rig_anchors)
                        .chain()
                        .before(OutlineBuild)
                        .before(TickSet::Topology),
                    coupling::follow_bodies.in_set(TickSet::Prepare),
                    coupling::load_body_masses
                        .after(TickSet::Gather)
                        .before(TickSet::Step),
                    coupling::push_bodies.after(TickSet::Writeback),
                ),
            )
            // A step taken again in halves must not count its impulses twice.
            .roll_back::<BodyCoupling, BodyCoupling>(
                |coupling, saved| saved.copy_from(coupling),
                |coupling, saved| coupling.copy_from(saved),
            )
            .add_systems(
                StrandsStep,
                (
                    coupling::record_velocities
                        .in_set(StepSet::Constrain)
                        .before(ConstrainSet::Project),
                    coupling::accumulate_impulses
                        .in_set(StepSet::Collide)
                        .after(CollideSet::Account),
                ),
            );
        if self.share_gravity {
            app.add_systems(StrandsTick, share_gravity.in_set(TickSet::Prepare));
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

/// The outline of each newly marked collider, its vertices attached to the collider's
/// body (or, for a collider without a body, to its transform).
#[allow(clippy::type_complexity)]
fn build_body_outlines(
    mut commands: Commands,
    colliders: Query<
        (
            Entity,
            &Collider,
            &CollidesWithStrands,
            Option<&avian2d::prelude::ColliderOf>,
            Option<&avian2d::prelude::Position>,
            Option<&Rotation>,
            &GlobalTransform,
        ),
        Without<AvianOutline>,
    >,
    bodies: Query<(
        &avian2d::prelude::Position,
        &Rotation,
        &RigidBody,
        &ComputedCenterOfMass,
    )>,
) {
    for (entity, collider, marker, of, position, rotation, transform) in &colliders {
        commands.entity(entity).insert(AvianOutline);
        let (points, closed) =
            match shapes::shape_outline(collider.shape_scaled().as_typed_shape(), marker.tolerance)
            {
                Ok(outline) => outline,
                Err(what) => {
                    warn!("bevy_strands: collider {entity} is {what}: strands pass through it");
                    continue;
                }
            };
        let body_entity = of.map_or(entity, |of| of.body);
        let Ok((body_position, body_rotation, body, centre_of_mass)) = bodies.get(body_entity)
        else {
            // No rigid body: a fixed shape where its transform puts it.
            spawn_anchored_outline(&mut commands, entity, &points, closed, transform);
            insert_shape(&mut commands, entity, points, closed, marker.tolerance);
            continue;
        };
        // The collider's own pose where avian keeps one (a child collider), else the
        // body's.
        let (at, turn) = match (position, rotation) {
            (Some(p), Some(r)) => (p.0, *r),
            _ => (body_position.0, *body_rotation),
        };
        let world = |p: Vec2| at + turn * p;
        let offset = |p: Vec2| body_rotation.inverse() * (world(p) - body_position.0);
        let world_point = |p: Vec2| world(p).as_dvec2();
        let anchor = |p: Vec2| BodyAnchor {
            body: body_entity,
            offset: offset(p),
        };
        if !body.is_dynamic() {
            // A body that forces do not move drives its outline from the start.
            spawn_outline(&mut commands, entity, &points, closed, world_point, |p| {
                (anchor(p), Kinematic)
            });
        } else {
            let offsets: Vec<Vec2> = points.iter().map(|&p| offset(p)).collect();
            let spread: f64 = offsets
                .iter()
                .map(|&o| (o - centre_of_mass.0).length_squared() as f64)
                .sum();
            let role = OutlineVertex {
                centre: false,
                vertices: points.len() as u32,
                inverse_spread: 1.0 / spread,
                framed: closed,
            };
            let spawned = spawn_outline(&mut commands, entity, &points, closed, world_point, |p| {
                (anchor(p), role)
            });
            if let (Some((_, vertices)), true) = (spawned, closed) {
                let body_world = |p: Vec2| (body_position.0 + *body_rotation * p).as_dvec2();
                spawn_truss(
                    &mut commands,
                    (entity, body_entity),
                    (&vertices, &offsets),
                    centre_of_mass.0,
                    role,
                    body_world,
                );
            }
        }
        insert_shape(&mut commands, entity, points, closed, marker.tolerance);
    }
}

/// The collider's outline as a [`StrandCollider`] too, so it is seen (and removed) as
/// every other collider outline is.
fn insert_shape(
    commands: &mut Commands,
    entity: Entity,
    points: Vec<Vec2>,
    closed: bool,
    tolerance: f32,
) {
    commands.entity(entity).insert(StrandCollider {
        shape: ColliderShape::Polyline { points, closed },
        tolerance,
    });
}

/// A collider no longer marked (or no longer a collider) loses its outline.
#[allow(clippy::type_complexity)]
fn drop_unmarked(
    mut commands: Commands,
    outlined: Query<
        Entity,
        (
            With<AvianOutline>,
            Or<(Without<CollidesWithStrands>, Without<Collider>)>,
        ),
    >,
) {
    for entity in &outlined {
        // The outline strand goes with the collider's StrandCollider.
        commands
            .entity(entity)
            .remove::<(AvianOutline, StrandCollider)>();
    }
}
