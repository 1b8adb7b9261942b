//! Two-way coupling of particles with rigid bodies, through the engine-neutral
//! [`BodyView`] and [`BodyPush`].
//!
//! A particle attached to a dynamic body ([`BodyAnchor`](super::BodyAnchor)) is simulated, for the tick,
//! as a free particle carrying a share of the body's mass: a vertex or the centre of
//! the body's frame ([`truss`](super::truss)) its share of the frame, a lone anchor the
//! body's effective mass along its edge on top of its own. Gravity, the strands'
//! constraints and contacts act on particle and body together, inside the exact
//! projection.
//!
//! A body with a frame is handed over ([`handoff`](super::handoff)): the strands
//! integrate it through the tick and write its state at the tick's end into the engine
//! ([`BodyPush::state`], remembered in [`BodyHeld`]); the engine steps it from there,
//! and what that step did besides gravity (its velocity against the one written, less
//! gravity's share) acts on the frame through the next tick as an acceleration. Its
//! frame starts each tick where the strands left it. Only on its first tick, or when
//! the engine put it somewhere else (a teleport), does the frame start where the
//! engine has the body, with its velocity.
//!
//! A lone anchor (on a body with no frame) starts each tick where the body has it;
//! every step the impulse the constraints and contacts gave it is measured (its
//! momentum after the collision stage less after the predictor), with its moment
//! about the body's centre of mass, and at the tick's end the body's share goes to the
//! body as a force and a torque over the engine's next step ([`BodyPush`]). A particle
//! on a static or kinematic body is [`Kinematic`] instead: infinite mass, moving with
//! the body.

use bevy::math::DVec2;
use bevy::prelude::*;

use super::carry::{HeldFrame, carried_state, fit_frame, frame_motion, held_frame, near_strands};
use super::coupled::{AnchorData, Coupled};
use super::handoff::BodyState;
use super::shapes::effective_mass;
use super::truss::BodyTruss;
use super::view::{BodyHeld, BodyPush, BodyView};
use crate::contact_events::TouchingPairs;
use crate::world::config::{CollisionConfig, StrandsConfig};
use crate::world::particle::{Kinematic, Particle, Position, SolverIndex, Velocity};
use crate::world::problems::InputProblems;
use crate::world::state::{ParticleState, copy_buffer};
use crate::world::strand::{Strand, StrandOf};

/// Ticks over which a frame that strands touched last tick is driven to its engine's
/// pose. The engine integrates the body in one step with last tick's impulses, the
/// strands in substeps: their poses part by up to about `g dt²/2` a tick while the body
/// moves, and a frame driven all the way back each tick pushes the strands it lies on
/// by that much, which they push back into the engine — crates on a rope bridge rocked
/// at 5–20 mm/s. Driven over this many ticks they come to rest; a frame nothing
/// touches is driven in one (it pushes nothing, and stays within a millimetre of its
/// body while it falls).
const TOUCHED_FRAME_TICKS: f64 = 24.0;

/// A frame's net impulse over a tick (kg·m/s) above which strands touched it.
const TOUCH_IMPULSE: f64 = 1e-9;

/// The particles coupled to dynamic bodies this tick, and their impulses.
#[derive(Resource, Default, Debug)]
pub struct BodyCoupling {
    coupled: Vec<Coupled>,
    velocity_before: Vec<DVec2>,
    /// The bodies with frames, each tick: held (`true`) or placed anew.
    frames: Vec<(HeldFrame, bool)>,
    /// Each body with the strands of its own (its outline, frame and the ropes tied to
    /// it), as (body, strand), this tick, sorted.
    own: Vec<(Entity, Entity)>,
    /// Scratch for a frame's rigid fit.
    fit: (Vec<DVec2>, Vec<DVec2>, Vec<f64>),
}

impl BodyCoupling {
    /// Become a copy of `other`, reusing this one's buffers.
    pub fn copy_from(&mut self, other: &BodyCoupling) {
        copy_buffer(&mut self.coupled, &other.coupled);
        copy_buffer(&mut self.velocity_before, &other.velocity_before);
        copy_buffer(&mut self.frames, &other.frames);
    }

    /// Whether the strands integrate `body` this tick (it has a frame).
    pub fn holds(&self, body: Entity) -> bool {
        self.frames.iter().any(|(f, _)| f.body == body)
    }

    /// Each body with the strands of its own (its outline, frame and the ropes tied
    /// to it), as (body, strand), this tick, sorted.
    pub fn own_strands(&self) -> &[(Entity, Entity)] {
        &self.own
    }

    /// Whether any simulated particle is coupled to a body this tick.
    pub fn couples(&self) -> bool {
        self.coupled.iter().any(|c| c.index != u32::MAX)
    }

    /// The impulse each coupled particle's body received in the last tick, as
    /// (particle, body, impulse), in a fixed order.
    pub fn impulses(&self) -> impl Iterator<Item = (Entity, Entity, DVec2)> + '_ {
        self.coupled
            .iter()
            .filter(|c| c.index != u32::MAX)
            .map(|c| (c.particle, c.body, c.impulse * (c.body_mass / c.total_mass)))
    }
}

/// Each body anchor's velocity for the tick, the coupled particles' body masses, and
/// kinematic markers where the body does not move under forces.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(super) fn follow_bodies(
    mut commands: Commands,
    config: Res<StrandsConfig>,
    mut coupling: ResMut<BodyCoupling>,
    mut particles: Query<AnchorData>,
    mut positions: ParamSet<(
        Query<&Position>,
        Query<&mut Position>,
        Query<(&Position, Option<&StrandOf>), With<Particle>>,
    )>,
    strands: Query<&Strand>,
    bodies: Query<(&BodyView, &BodyHeld)>,
    collisions: Res<CollisionConfig>,
    mut moves: Local<Vec<(Entity, DVec2)>>,
    mut lone_anchors: Local<Vec<(Entity, Entity, DVec2, DVec2, DVec2)>>,
    mut touched: Local<Vec<(Entity, DVec2)>>,
    mut problems: ResMut<InputProblems>,
    (trusses, mut scratch): (Query<&BodyTruss>, Local<(Vec<Entity>, Vec<Entity>)>),
) {
    // The framed bodies strands pushed last tick (their frame's impulses, whose inner
    // edges' cancel, sum to more than round-off).
    touched.clear();
    let frames = coupling.coupled.iter().filter(|c| c.replaces);
    for c in frames {
        match touched.last_mut() {
            Some((body, sum)) if *body == c.body => *sum += c.impulse,
            _ => touched.push((c.body, c.impulse)),
        }
    }
    touched.retain(|(_, sum)| sum.length() > TOUCH_IMPULSE);
    coupling.coupled.clear();
    lone_anchors.clear();
    coupling.frames.clear();
    let tick = config.tick_seconds();
    if !(tick.is_finite() && tick > 0.0) {
        return;
    }
    // A lone anchor coupled to a dynamic body starts the tick where the body has it, when
    // it is that close: moved by so little no strand can be passed, and with no
    // velocity of its own to bring it back, so nothing the body did not do is fed
    // back to it.
    let snap = 0.25 * collisions.thickness;
    moves.clear();
    let (near, tied) = &mut *scratch;
    near_strands(
        (near, &mut coupling.own, tied),
        (&particles, &bodies, &trusses),
        &positions.p2(),
        (tick, collisions.thickness),
    );
    let positions_now = positions.p0();
    for (entity, anchor, mut velocity, kinematic, vertex, rigged, strand) in &mut particles {
        let Ok(position) = positions_now.get(entity) else {
            continue;
        };
        let Ok((body, held)) = bodies.get(anchor.body) else {
            problems.report(
                entity,
                format!(
                    "body anchor {} is not a rigid body: held still",
                    anchor.body
                ),
            );
            velocity.set_if_neq(Velocity(DVec2::ZERO));
            continue;
        };
        let offset = rigged.map_or(anchor.offset, |r| r.offset);
        let (point, point_velocity, arm) = body.point_motion(offset);
        // A body its engine has put to sleep holds still where its particles are (not
        // moved to the engine's pose: a jump no contact would see), a wall to the
        // strands until one that has not settled touches it and wakes it (`rest`).
        if body.is_dynamic() && body.sleeping {
            velocity.set_if_neq(Velocity(DVec2::ZERO));
            if !kinematic {
                commands.entity(entity).insert(Kinematic);
            }
            continue;
        }
        let dynamic = body.is_dynamic();
        let framed = vertex.is_some() || rigged.is_some();
        // A frame the strands handed over last tick carries on from where they left it.
        let handed = dynamic && framed && body.has_mass() && !near.contains(&anchor.body) && {
            let (_, handed) = held_frame(
                &mut coupling.frames,
                anchor.body,
                body,
                held,
                (tick, config.gravity),
                collisions.thickness,
            );
            handed
        };
        let off = point - position.0;
        let lone = dynamic && !framed && body.has_mass();
        if lone {
            // Placed once it is known whether it is its body's only one.
            lone_anchors.push((entity, anchor.body, point, point_velocity, off));
        } else if handed {
            // Where the strands left it, moving with the body as handed over: a rigid
            // motion, whatever the last tick's position corrections left in its
            // velocity.
            if rigged.is_none()
                && let Some((frame, _)) =
                    coupling.frames.iter().find(|(f, _)| f.body == anchor.body)
            {
                let arm = position.0 - frame.centre;
                let rigid = frame.start.linear.as_dvec2() + frame.start.angular as f64 * arm.perp();
                velocity.set_if_neq(Velocity(rigid));
            }
        } else if dynamic && !framed && off.length() < snap {
            moves.push((entity, point));
            velocity.set_if_neq(Velocity(point_velocity));
        } else {
            // A frame's vertex is never moved there: the frame would jump, and a strand
            // lying against it could end up inside (a crate's corner through the rope
            // bridge it rests on). Driven there through the tick, the contacts see it.
            // One still marked kinematic has just woken (or just turned dynamic): its
            // frame may lie off its engine's pose by what the slow drive left, met
            // as slowly.
            let ticks = if kinematic || touched.iter().any(|(body, _)| *body == anchor.body) {
                TOUCHED_FRAME_TICKS
            } else {
                1.0
            };
            velocity.set_if_neq(Velocity(point_velocity + off / (ticks * tick)));
        }
        if dynamic == kinematic {
            if dynamic {
                commands.entity(entity).remove::<Kinematic>();
            } else {
                commands.entity(entity).insert(Kinematic);
            }
        }
        // Tied into the body's frame: the frame carries the body.
        if !dynamic || rigged.is_some() {
            continue;
        }
        // A body the engine has not given its mass properties yet (spawned this frame)
        // is followed, not coupled.
        if !body.has_mass() {
            continue;
        }
        let (mass, inertia) = (body.mass as f64, body.inertia as f64);
        let body_mass = match vertex {
            Some(vertex) => vertex.mass(mass, inertia),
            None => {
                // A rope's end meets the body along its first edge.
                let direction = neighbour(entity, strand, &strands, &positions_now)
                    .map(|x| (x - position.0).normalize_or_zero().as_vec2())
                    .filter(|n| *n != Vec2::ZERO);
                effective_mass(mass, inertia, arm, direction)
            }
        };
        coupling.coupled.push(Coupled {
            particle: entity,
            body: anchor.body,
            index: u32::MAX,
            body_mass,
            replaces: vertex.is_some(),
            total_mass: 0.0,
            arm,
            impulse: DVec2::ZERO,
            angular: 0.0,
            offset,
            hub: vertex.is_some_and(|v| v.centre),
            handover: false,
        });
    }
    // A body's only lone anchor carries the whole body, handed over through it: it
    // starts the tick at the hook, moving with the body's centre of mass.
    for &(entity, body_entity, point, point_velocity, off) in lone_anchors.iter() {
        let alone = coupling.frames.iter().all(|(f, _)| f.body != body_entity)
            && lone_anchors.iter().filter(|l| l.1 == body_entity).count() == 1;
        let start = alone
            .then(|| bodies.get(body_entity).ok())
            .flatten()
            .map(|(body, held)| {
                let (frame, _) = held_frame(
                    &mut coupling.frames,
                    body_entity,
                    body,
                    held,
                    (tick, config.gravity),
                    collisions.thickness,
                );
                (frame, body.mass as f64)
            });
        let Ok((_, anchor, mut velocity, ..)) = particles.get_mut(entity) else {
            continue;
        };
        if let Some((mut frame, mass)) = start {
            frame.lone = true;
            if let Some(record) = coupling
                .frames
                .iter_mut()
                .find(|(f, _)| f.body == body_entity)
            {
                record.0.lone = true;
            }
            let (hook, _, arm) = frame.start.point_motion(anchor.offset);
            moves.push((entity, hook));
            velocity.set_if_neq(Velocity(frame.start.linear.as_dvec2()));
            if let Some(c) = coupling.coupled.iter_mut().find(|c| c.particle == entity) {
                c.body_mass = mass;
                c.arm = arm;
                c.handover = true;
            }
        } else if off.length() < snap {
            moves.push((entity, point));
            velocity.set_if_neq(Velocity(point_velocity));
        } else {
            velocity.set_if_neq(Velocity(point_velocity + off / tick));
        }
    }
    let mut positions_mut = positions.p1();
    for &(entity, point) in moves.iter() {
        if let Ok(mut position) = positions_mut.get_mut(entity) {
            position.0 = point;
        }
    }
    share_among_anchors(&mut coupling.coupled);
    // Each body's frame together, in a fixed order (the query's order is the archetype
    // storage's).
    coupling
        .coupled
        .sort_by_key(|c| (c.body, !c.replaces, c.particle));
}

/// Several lone anchors on one body share it: each carries its effective mass divided
/// by their number, so that together they never ask more of the body than it has.
fn share_among_anchors(coupled: &mut [Coupled]) {
    for k in 0..coupled.len() {
        if coupled[k].replaces || coupled[k].handover {
            continue;
        }
        let body = coupled[k].body;
        let count = coupled
            .iter()
            .filter(|c| !c.replaces && c.body == body)
            .count();
        coupled[k].body_mass /= count as f64;
    }
}

/// Where the particle's strand neighbour is (the next particle, or the previous at the
/// strand's end).
fn neighbour(
    particle: Entity,
    strand: Option<&StrandOf>,
    strands: &Query<&Strand>,
    positions: &Query<&Position>,
) -> Option<DVec2> {
    let strand = strands.get(strand?.0).ok()?;
    let k = strand.particles.iter().position(|&p| p == particle)?;
    let n = strand.particles.len();
    let other = if k + 1 < n {
        k + 1
    } else if strand.closed {
        0
    } else {
        k.checked_sub(1)?
    };
    positions.get(strand.particles[other]).ok().map(|p| p.0)
}

/// After the gather: the coupled particles' masses in the packed state.
pub(super) fn load_body_masses(
    mut coupling: ResMut<BodyCoupling>,
    indices: Query<&SolverIndex>,
    mut state: ResMut<ParticleState>,
) {
    let coupling = &mut *coupling;
    for c in &mut coupling.coupled {
        c.index = u32::MAX;
        let Some(i) = indices.get(c.particle).ok().and_then(|s| s.get()) else {
            continue;
        };
        // Pinned, frozen or still kinematic this tick: the body moves it, no coupling.
        if i >= state.len() || state.is_pinned(i) {
            continue;
        }
        let own = if c.replaces { 0.0 } else { state.mass[i] };
        c.total_mass = own + c.body_mass;
        if !(c.total_mass.is_finite() && c.total_mass > 0.0) {
            continue;
        }
        state.mass[i] = c.total_mass;
        state.inverse_mass[i] = 1.0 / c.total_mass;
        c.index = i as u32;
        // What the engine did to a handed-over body acts on its frame all tick.
        if let Some((frame, true)) = coupling.frames.iter().find(|(f, _)| f.body == c.body) {
            // A lone anchor moves with the centre of mass; its body turns apart.
            let turn = if frame.lone {
                DVec2::ZERO
            } else {
                frame.angular * (state.position[i] - frame.centre).perp()
            };
            state.external_force[i] += c.total_mass * (frame.linear + turn);
        }
    }
    coupling.velocity_before.clear();
    coupling
        .velocity_before
        .resize(coupling.coupled.len(), DVec2::ZERO);
}

/// Each step, before the constraints: the coupled particles' predicted velocities.
pub(super) fn record_velocities(mut coupling: ResMut<BodyCoupling>, state: Res<ParticleState>) {
    let coupling = &mut *coupling;
    for (c, before) in coupling.coupled.iter().zip(&mut coupling.velocity_before) {
        if let Some(v) = state.velocity.get(c.index as usize) {
            *before = *v;
        }
    }
}

/// Each step, after the collisions: the impulse constraints and contacts gave, and
/// its moment about the body's centre of mass. A frame's centre of mass is its own,
/// where its particles are in this step, so its inner edges add no moment; a lone
/// anchor's arm is the one it had on the body at the tick's start.
pub(super) fn accumulate_impulses(mut coupling: ResMut<BodyCoupling>, state: Res<ParticleState>) {
    let coupling = &mut *coupling;
    let (coupled, before) = (&mut coupling.coupled, &coupling.velocity_before);
    let mut start = 0;
    while start < coupled.len() {
        let (body, frame) = (coupled[start].body, coupled[start].replaces);
        let end = start
            + coupled[start..]
                .iter()
                .take_while(|c| c.body == body && c.replaces == frame)
                .count();
        let members = start..end;
        let live = |c: &Coupled| (c.index as usize) < state.len();
        let (weighted, mass) = coupled[members.clone()].iter().filter(|c| live(c)).fold(
            (DVec2::ZERO, 0.0),
            |(x, m), c| {
                (
                    x + c.total_mass * state.position[c.index as usize],
                    m + c.total_mass,
                )
            },
        );
        let centre = if mass > 0.0 {
            weighted / mass
        } else {
            DVec2::ZERO
        };
        for k in members {
            let c = &mut coupled[k];
            if !live(c) {
                continue;
            }
            let i = c.index as usize;
            let impulse = c.total_mass * (state.velocity[i] - before[k]);
            c.impulse += impulse;
            let arm = if frame {
                state.position[i] - centre
            } else {
                c.arm.as_dvec2()
            };
            c.angular += arm.perp_dot(impulse);
        }
        start = end;
    }
}

/// At the tick's end: each framed body's state, fitted to its frame, for the engine to
/// step from (and remembered); for lone anchors, the body's share of their impulses and
/// its moment, as a force and a torque spread over the engine's next step, which covers
/// the same time. Spread, not at once: gravity acts on the body through that step, and
/// a rope that holds the body up must act with it, or the body jumps up and falls back
/// every tick.
pub(super) fn push_bodies(
    mut coupling: ResMut<BodyCoupling>,
    config: Res<StrandsConfig>,
    state: Res<ParticleState>,
    mut bodies: Query<(&mut BodyPush, &mut BodyHeld)>,
    (trusses, touching): (Query<&BodyTruss>, Res<TouchingPairs>),
) {
    let coupling = &mut *coupling;
    let tick = config.tick_seconds();
    // A frame that touched a strand this tick (one `near_strands` did not foresee)
    // leaves it handed over, and goes to the force from the next.
    // Its own rope brushing it does not count: that rope weighs next to nothing
    // against it.
    let own = &coupling.own;
    let foreign = |body: Entity, other: Entity| own.binary_search(&(body, other)).is_err();
    let touched = |body: Entity| {
        trusses.get(body).is_ok_and(|truss| {
            let c = truss.collider;
            let mut pairs = touching.current.iter();
            pairs.any(|&(a, b)| (a == c && foreign(body, b)) || (b == c && foreign(body, a)))
        })
    };
    for k in 0..coupling.frames.len() {
        let frame = coupling.frames[k].0;
        let fitted = if frame.lone {
            carried_state(&coupling.coupled, &state, frame, tick)
        } else {
            // Away from contact the frame's own rigid motion; one that met a strand
            // this tick leaves with the momentum its impulses gave it, without what
            // the contact's position corrections left in its particles' velocities.
            fit_frame(&coupling.coupled, &mut coupling.fit, &state, frame).map(|pose| {
                if !touched(frame.body) {
                    return pose;
                }
                let (linear, angular) =
                    frame_motion(&coupling.coupled, frame, (tick, config.gravity));
                BodyState {
                    linear,
                    angular,
                    ..pose
                }
            })
        };
        if let Ok((mut push, mut held)) = bodies.get_mut(frame.body) {
            push.state = fitted;
            // One that met a strand after all goes to the engine's force from the
            // next tick on.
            let next = if touched(frame.body) { None } else { fitted };
            held.set_if_neq(BodyHeld(next));
        }
    }
    for c in coupling.coupled.iter().filter(|c| c.index != u32::MAX) {
        let handed = coupling.frames.iter().any(|(f, _)| f.body == c.body);
        if !handed && let Ok((_, mut held)) = bodies.get_mut(c.body) {
            // The engine integrates it this tick: the next hand-over starts afresh.
            held.set_if_neq(BodyHeld(None));
        }
        if handed && (c.replaces || c.handover) {
            continue;
        }
        let share = c.body_mass / c.total_mass / tick;
        let (force, torque) = (c.impulse * share, c.angular * share);
        if !(force.is_finite() && torque.is_finite()) {
            continue;
        }
        if let Ok((mut push, _)) = bodies.get_mut(c.body) {
            push.force += force.as_vec2();
            push.torque += torque as f32;
        }
    }
}
