//! Two-way coupling of particles with rigid bodies, through the engine-neutral
//! [`BodyView`] and [`BodyPush`].
//!
//! A particle attached to a dynamic body ([`BodyAnchor`]) is simulated, for the tick,
//! as a free particle carrying a share of the body's mass: a vertex or the centre of
//! the body's frame ([`truss`](super::truss)) its share of the frame, a lone anchor the
//! body's effective mass along its edge on top of its own. It starts the tick where the
//! body has it, with the body's velocity there, so gravity, the strands' constraints
//! and contacts act on particle and body together, inside the exact projection. Every
//! step the impulse the constraints and contacts gave it is measured (its momentum
//! after the collision stage less after the predictor), with its moment about the
//! body's centre of mass; at the tick's end the body's share goes to the body as a
//! force and a torque over the engine's next step ([`BodyPush`]). A particle on a static or kinematic body
//! is [`Kinematic`] instead: infinite mass, moving with the body.

use bevy::math::DVec2;
use bevy::prelude::*;

use super::anchor::BodyAnchor;
use super::shapes::effective_mass;
use super::truss::{OutlineVertex, Rigged};
use super::view::{BodyPush, BodyView};
use crate::world::config::{CollisionConfig, StrandsConfig};
use crate::world::particle::{Kinematic, Position, SolverIndex, Velocity};
use crate::world::problems::InputProblems;
use crate::world::state::{ParticleState, copy_buffer};
use crate::world::strand::{Strand, StrandOf};

/// One particle coupled to a dynamic body this tick.
#[derive(Clone, Copy, Debug)]
struct Coupled {
    particle: Entity,
    body: Entity,
    /// Packed index, `u32::MAX` until the gather (or if it is not simulated).
    index: u32,
    /// The body's effective mass at the particle.
    body_mass: f64,
    /// Whether the particle's own mass is replaced (an outline vertex) or added to.
    replaces: bool,
    /// The particle's mass in the solve.
    total_mass: f64,
    /// The arm from the body's centre of mass at the tick's start (a lone anchor's
    /// torque arm).
    arm: Vec2,
    /// Constraint and contact impulse on the particle so far this tick.
    impulse: DVec2,
    /// Its angular impulse about the body's centre of mass so far this tick.
    angular: f64,
}

/// The particles coupled to dynamic bodies this tick, and their impulses.
#[derive(Resource, Default, Debug)]
pub struct BodyCoupling {
    coupled: Vec<Coupled>,
    velocity_before: Vec<DVec2>,
}

impl BodyCoupling {
    /// Become a copy of `other`, reusing this one's buffers.
    pub fn copy_from(&mut self, other: &BodyCoupling) {
        copy_buffer(&mut self.coupled, &other.coupled);
        copy_buffer(&mut self.velocity_before, &other.velocity_before);
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

/// What the coupling reads and writes of an anchored particle.
type AnchorData = (
    Entity,
    &'static BodyAnchor,
    &'static mut Velocity,
    Has<Kinematic>,
    Option<&'static OutlineVertex>,
    Option<&'static Rigged>,
    Option<&'static StrandOf>,
);

/// Each body anchor's velocity for the tick, the coupled particles' body masses, and
/// kinematic markers where the body does not move under forces.
#[allow(clippy::too_many_arguments)]
pub(super) fn follow_bodies(
    mut commands: Commands,
    config: Res<StrandsConfig>,
    mut coupling: ResMut<BodyCoupling>,
    mut particles: Query<AnchorData>,
    mut positions: ParamSet<(Query<&Position>, Query<&mut Position>)>,
    strands: Query<&Strand>,
    bodies: Query<&BodyView>,
    collisions: Res<CollisionConfig>,
    mut moves: Local<Vec<(Entity, DVec2)>>,
    mut problems: ResMut<InputProblems>,
) {
    coupling.coupled.clear();
    let tick = config.tick_seconds();
    if !(tick.is_finite() && tick > 0.0) {
        return;
    }
    // A particle coupled to a dynamic body starts the tick where the body has it, when
    // it is that close: moved by so little no strand can be passed, and with no
    // velocity of its own to bring it back, so nothing the body did not do is fed
    // back to it.
    let snap = 0.25 * collisions.thickness;
    moves.clear();
    let positions_now = positions.p0();
    for (entity, anchor, mut velocity, kinematic, vertex, rigged, strand) in &mut particles {
        let Ok(position) = positions_now.get(entity) else {
            continue;
        };
        let Ok(body) = bodies.get(anchor.body) else {
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
        let dynamic = body.is_dynamic();
        let off = point - position.0;
        if dynamic && off.length() < snap {
            moves.push((entity, point));
            velocity.set_if_neq(Velocity(point_velocity));
        } else {
            velocity.set_if_neq(Velocity(point_velocity + off / tick));
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
        });
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
        if coupled[k].replaces {
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

/// At the tick's end: each body's share of its particles' impulses and their moments,
/// as a force and a torque spread over the engine's next step, which covers the same
/// time.
/// Spread, not at once: gravity acts on the body through that step, and a rope that
/// holds the body up must act with it, or the body jumps up and falls back every tick.
pub(super) fn push_bodies(
    coupling: Res<BodyCoupling>,
    config: Res<StrandsConfig>,
    mut bodies: Query<&mut BodyPush>,
) {
    let tick = config.tick_seconds();
    for c in coupling.coupled.iter().filter(|c| c.index != u32::MAX) {
        let share = c.body_mass / c.total_mass / tick;
        let (force, torque) = (c.impulse * share, c.angular * share);
        if !(force.is_finite() && torque.is_finite()) {
            continue;
        }
        if let Ok(mut push) = bodies.get_mut(c.body) {
            push.force += force.as_vec2();
            push.torque += torque as f32;
        }
    }
}
