//! Strands coupled with a rigid-body engine, written once for every engine.
//!
//! - A collider marked [`CollidesWithStrands`] gets an outline strand, as the crate's
//!   own [`StrandCollider`]s do: strands meet it through the same continuous
//!   detection, impulses and fail-safe. On a dynamic body the outline is a rigid frame
//!   carrying the body's mass and inertia ([`truss`]), and what strands push on it goes
//!   back to the body ([`coupling`]).
//! - A body with a rope tied to it is handed over ([`handoff`]): the strands integrate
//!   it through each tick and write its state into the engine, so a heavy load on a
//!   rope swings with no energy from the coupling.
//! - A particle with a [`BodyAnchor`] hangs on a body: a crate on a rope pulls the rope
//!   down and the rope holds it up, with every edge exact.
//!
//! The engine is behind a small interface: its adapter (the avian and rapier modules,
//! which import this one) mirrors each body's pose, velocity and mass properties into a
//! [`BodyView`] in [`BodySync::Read`], hands each new marked collider's outline to
//! `outline_collider`, and applies each [`BodyPush`] with its own force API in
//! [`BodySync::Write`]. This module imports no engine.
//!
//! Imports: [`crate::model`], [`crate::world`], [`crate::schedule`], [`crate::halving`],
//! [`crate::colliders`], [`crate::contact_events`], [`crate::sleeping`].

pub mod anchor;
mod carry;
mod coupled;
pub mod coupling;
pub mod handoff;
mod rest;
pub mod shapes;
pub mod truss;
pub mod view;

use std::marker::PhantomData;

use bevy::ecs::schedule::ScheduleConfigs;
use bevy::ecs::system::ScheduleSystem;
use bevy::prelude::*;

use crate::colliders::{
    ColliderShape, OutlineBuild, StrandCollider, spawn_anchored_outline, spawn_outline,
};
use crate::halving::{HalvingApp, HalvingSaves};
use crate::schedule::{CollideSet, ConstrainSet, StepSet, StrandsStep, StrandsTick, TickSet};
use crate::world::particle::Kinematic;
pub use anchor::BodyAnchor;
pub use coupling::BodyCoupling;
pub use handoff::BodyState;
use truss::{OutlineVertex, spawn_truss};
pub use view::{BodyHeld, BodyMotion, BodyPush, BodyView, planar_rotation, spawn_state};

/// Make strands collide with this collider (avian's or Rapier's), its curves drawn
/// within `tolerance`.
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

/// Where an engine's adapter meets the coupling in [`StrandsTick`].
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BodySync {
    /// Bodies mirrored into [`BodyView`]s and new colliders outlined: before the tick.
    Read,
    /// [`BodyPush`]es handed to the engine: after the tick.
    Write,
}

/// The engine-neutral half of the coupling: added by each engine's plugin (once,
/// whichever engines a game uses).
pub(crate) struct BodyCouplingPlugin;

impl Plugin for BodyCouplingPlugin {
    fn build(&self, app: &mut App) {
        // No step that couples a body is taken again in halves: the engine moves its
        // bodies between ticks, so an anchored end starts the tick off its length by
        // what the engine moved it, and half the step corrects that twice as fast (a
        // rope of a two-thousandth of its crate flew apart).
        app.init_resource::<HalvingSaves>();
        app.world_mut()
            .resource_mut::<HalvingSaves>()
            .forbid_when(|world| {
                world
                    .get_resource::<BodyCoupling>()
                    .is_some_and(BodyCoupling::couples)
            });
        app.register_type::<CollidesWithStrands>()
            .register_type::<BodyAnchor>()
            .register_type::<BodyView>()
            .init_resource::<BodyCoupling>()
            .configure_sets(
                StrandsTick,
                (
                    // Outlines and ties exist before the bodies are followed, so that a
                    // new body's frame is coupled from its first tick.
                    BodySync::Read
                        .before(TickSet::Prepare)
                        .before(OutlineBuild)
                        .before(TickSet::Topology),
                    BodySync::Write.after(TickSet::Writeback),
                ),
            )
            .add_systems(
                StrandsTick,
                (
                    // Before the bodies are followed, so that new ties start taut.
                    (drop_unmarked, truss::rig_anchors)
                        .chain()
                        .after(BodySync::Read)
                        .before(TickSet::Prepare)
                        .before(OutlineBuild)
                        .before(TickSet::Topology),
                    coupling::follow_bodies.in_set(TickSet::Prepare),
                    coupling::load_body_masses
                        .after(TickSet::Gather)
                        .before(TickSet::Step),
                    // Before this tick's contacts are turned into messages (and kept
                    // as the last tick's).
                    coupling::push_bodies
                        .after(TickSet::Writeback)
                        .before(crate::contact_events::write_messages)
                        .before(BodySync::Write),
                    // With this tick's rest times and contacts.
                    rest::settle_bodies
                        .after(coupling::push_bodies)
                        .after(crate::sleeping::tally)
                        .before(crate::contact_events::write_messages)
                        .before(BodySync::Write),
                ),
            )
            // A step taken again in halves must not count its impulses twice.
            .save_for_halving::<BodyCoupling, BodyCoupling>(
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
    }
}

/// What every engine's adapter registers, once for `Body` (its rigid-body component)
/// and `C` (its collider component): the engine-neutral coupling (once for all
/// engines), the mirror components on every body, and its own systems — `mirror`
/// (bodies into [`BodyView`]s) then `build` (new outlines, after those no longer `C`'s
/// are dropped) before the tick, `write` (each [`BodyPush`] into the engine) after it.
pub(crate) fn add_adapter<Body: Component, C: Component, M, B, W>(
    app: &mut App,
    mirror: impl IntoScheduleConfigs<ScheduleSystem, M>,
    build: impl IntoScheduleConfigs<ScheduleSystem, B>,
    write: impl IntoScheduleConfigs<ScheduleSystem, W>,
) {
    if !app.is_plugin_added::<BodyCouplingPlugin>() {
        app.add_plugins(BodyCouplingPlugin);
    }
    let read: ScheduleConfigs<ScheduleSystem> = (mirror, (drop_unowned::<C>, build).chain())
        .chain()
        .into_configs();
    app.register_required_components::<Body, BodyView>()
        .register_required_components::<Body, BodyPush>()
        .register_required_components::<Body, BodyHeld>()
        .add_systems(
            StrandsTick,
            (read.in_set(BodySync::Read), write.in_set(BodySync::Write)),
        );
}

/// On a collider whose outline was built from the engine collider `C`.
#[derive(Component)]
pub(crate) struct OutlinedFrom<C: Component>(PhantomData<fn() -> C>);

impl<C: Component> Default for OutlinedFrom<C> {
    fn default() -> Self {
        Self(PhantomData)
    }
}

/// A collider that is no longer the engine's `C` loses its outline.
fn drop_unowned<C: Component>(
    mut commands: Commands,
    outlined: Query<Entity, (With<OutlinedFrom<C>>, Without<C>)>,
) {
    for entity in &outlined {
        commands.entity(entity).remove::<OutlinedFrom<C>>();
        drop_outline(&mut commands, entity);
    }
}

/// On a collider whose outline the coupling built (or refused to build).
#[derive(Component, Clone, Copy, Debug, Default)]
pub(crate) struct BodyOutline;

/// A newly marked collider, as its engine's adapter sees it.
pub(crate) struct MarkedCollider<'a> {
    /// The collider entity.
    pub entity: Entity,
    /// Its outline in its own frame, or why it has none.
    pub outline: Result<(Vec<Vec2>, bool), String>,
    /// Its pose in its body's frame (origin, angle), and the body where the strands'
    /// tick takes it up ([`BodyView::at_tick_start`]), when it has one.
    pub body: Option<(Entity, &'a BodyView, Vec2, Rot2)>,
    /// Its world transform (for a collider with no body).
    pub transform: &'a GlobalTransform,
    /// The marker.
    pub marker: CollidesWithStrands,
}

/// Build a marked collider's outline, its vertices attached to its body (or, for a
/// collider without a body, to its transform): a kinematic or static body drives its
/// outline; a dynamic one gets a rigid frame carrying its mass.
pub(crate) fn outline_collider(commands: &mut Commands, collider: MarkedCollider<'_>) {
    let entity = collider.entity;
    commands.entity(entity).insert(BodyOutline);
    let (points, closed) = match collider.outline {
        Ok(outline) => outline,
        Err(what) => {
            warn!("bevy_strands: collider {entity} is {what}: strands pass through it");
            return;
        }
    };
    let tolerance = collider.marker.tolerance;
    let Some((body_entity, body, at, turn)) = collider.body else {
        // No rigid body: a fixed shape where its transform puts it.
        spawn_anchored_outline(commands, entity, &points, closed, collider.transform);
        insert_shape(commands, entity, points, closed, tolerance);
        return;
    };
    let offset = |p: Vec2| at + turn * p;
    let world_point = |p: Vec2| body.world_point(offset(p)).as_dvec2();
    let anchor = |p: Vec2| BodyAnchor {
        body: body_entity,
        offset: offset(p),
    };
    if !body.is_dynamic() {
        // A body that forces do not move drives its outline from the start.
        spawn_outline(commands, entity, &points, closed, world_point, |p| {
            (anchor(p), Kinematic)
        });
    } else {
        let offsets: Vec<Vec2> = points.iter().map(|&p| offset(p)).collect();
        let spread: f64 = offsets
            .iter()
            .map(|&o| (o - body.centre_of_mass).length_squared() as f64)
            .sum();
        let role = OutlineVertex {
            centre: false,
            vertices: points.len() as u32,
            inverse_spread: 1.0 / spread,
            framed: closed,
        };
        let spawned = spawn_outline(commands, entity, &points, closed, world_point, |p| {
            (anchor(p), role)
        });
        if let (Some((_, vertices)), true) = (spawned, closed) {
            spawn_truss(
                commands,
                (entity, body_entity),
                (&vertices, &offsets),
                body.centre_of_mass,
                role,
                |p| body.world_point(p).as_dvec2(),
            );
        }
    }
    insert_shape(commands, entity, points, closed, tolerance);
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

/// A collider no longer marked loses its outline (an adapter also drops one that is no
/// longer its engine's collider).
fn drop_unmarked(
    mut commands: Commands,
    outlined: Query<Entity, (With<BodyOutline>, Without<CollidesWithStrands>)>,
) {
    for entity in &outlined {
        drop_outline(&mut commands, entity);
    }
}

/// Whether two length units (world units per metre) agree.
pub(crate) fn same_length_unit(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs())
}

/// Remove a collider's outline (the outline strand goes with its StrandCollider).
fn drop_outline(commands: &mut Commands, entity: Entity) {
    commands
        .entity(entity)
        .remove::<(BodyOutline, StrandCollider)>();
}
