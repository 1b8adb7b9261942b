//! The bodies the strands carry through a tick (handed over, see
//! [`handoff`](super::handoff)): which are, where each starts, what the engine's own
//! step did to it, and its state at the tick's end — fitted to its frame, or carried by
//! its one lone anchor.

use bevy::math::{DVec2, Rot2};
use bevy::prelude::*;

use super::coupled::{AnchorData, Coupled};
use super::handoff::{BodyState, frame_state};
use super::truss::BodyTruss;
use super::view::{BodyHeld, BodyView};
use crate::world::particle::{Particle, Position};
use crate::world::state::ParticleState;
use crate::world::strand::StrandOf;

/// A body the strands integrate this tick, and what its engine's last step did to it
/// besides gravity.
#[derive(Clone, Copy, Debug)]
pub(super) struct HeldFrame {
    pub(super) body: Entity,
    /// The acceleration of its centre of mass.
    pub(super) linear: DVec2,
    /// Its angular acceleration.
    pub(super) angular: f64,
    /// Its centre of mass at the tick's start.
    pub(super) centre: DVec2,
    /// The engine's centre of mass (in the body's frame).
    pub(super) centre_of_mass: Vec2,
    /// The body where the tick takes it up.
    pub(super) start: BodyView,
    /// Whether a lone anchor carries it (no frame).
    pub(super) lone: bool,
}

/// The framed bodies not handed over this tick: those no rope is tied to (a crate
/// that only meets strands is the engine's), and those that a strand not their own
/// (outline, frame, a rope tied to them) is near — within their reach this tick. The
/// contact solve's position corrections at the coupling's step put energy into a body
/// integrated by the strands alone (a crate bounced off a rope bridge higher than it
/// fell), so their impulses go to the engine as a force.
pub(super) fn near_strands(
    (near, own, tied): (
        &mut Vec<Entity>,
        &mut Vec<(Entity, Entity)>,
        &mut Vec<Entity>,
    ),
    (anchored, bodies, trusses): (
        &Query<AnchorData>,
        &Query<(&BodyView, &BodyHeld)>,
        &Query<&BodyTruss>,
    ),
    particles: &Query<(&Position, Option<&StrandOf>), With<Particle>>,
    (tick, thickness): (f64, f64),
) {
    near.clear();
    own.clear();
    tied.clear();
    for (_, anchor, _, _, _, rigged, strand) in anchored.iter() {
        if let Some(strand) = strand {
            own.push((anchor.body, strand.0));
        }
        if rigged.is_some() {
            tied.push(anchor.body);
        }
    }
    // Each (body, strand) once, sorted: a body's strands side by side.
    own.sort_unstable();
    own.dedup();
    tied.sort_unstable();
    tied.dedup();
    for strands in own.chunk_by(|a, b| a.0 == b.0) {
        let body_entity = strands[0].0;
        if tied.binary_search(&body_entity).is_err() {
            near.push(body_entity);
            continue;
        }
        let (Ok((body, _)), Ok(truss)) = (bodies.get(body_entity), trusses.get(body_entity)) else {
            continue;
        };
        let radius = truss
            .offsets
            .iter()
            .map(|&o| (o - body.centre_of_mass).length() as f64)
            .fold(0.0, f64::max);
        let centre = body.world_point(body.centre_of_mass).as_dvec2();
        let reach = radius + 2.0 * body.linear.length() as f64 * tick + 3.0 * thickness;
        let foreign = |strand: Option<&StrandOf>| {
            strand.is_none_or(|s| strands.binary_search(&(body_entity, s.0)).is_err())
        };
        if particles
            .iter()
            .any(|(p, strand)| foreign(strand) && (p.0 - centre).length() < reach)
        {
            near.push(body_entity);
        }
    }
}

/// The record of a framed body this tick (made for its first particle): whether the
/// strands hand it over from the last tick (see [`BodyView::at_tick_start`]) and the
/// acceleration the engine's step gave it besides gravity.
pub(super) fn held_frame(
    frames: &mut Vec<(HeldFrame, bool)>,
    entity: Entity,
    body: &BodyView,
    held: &BodyHeld,
    (tick, gravity): (f64, DVec2),
    tolerance: f64,
) -> (HeldFrame, bool) {
    if let Some(found) = frames.iter().find(|(f, _)| f.body == entity) {
        return *found;
    }
    let (start, handed) = body.at_tick_start(held, tick, tolerance);
    let mut frame = HeldFrame {
        body: entity,
        linear: DVec2::ZERO,
        angular: 0.0,
        centre: start.world_point(start.centre_of_mass).as_dvec2(),
        centre_of_mass: body.centre_of_mass,
        start,
        lone: false,
    };
    // A sleeping body was not stepped.
    if handed && !body.sleeping {
        frame.linear = (body.linear - start.linear).as_dvec2() / tick - gravity;
        frame.angular = (body.angular - start.angular) as f64 / tick;
    }
    frames.push((frame, handed));
    (frame, handed)
}

/// The state of a body carried by its one lone anchor: its centre of mass where the
/// anchor took it (the hook's arm kept from the tick's start), moving as the anchor
/// does. Its rotation is the engine's: a lone anchor carries the body's mass, not its
/// inertia, so the strands' pull turns no body (tie the rope into a frame, with
/// [`CollidesWithStrands`](super::CollidesWithStrands), for that).
pub(super) fn carried_state(
    coupled: &[Coupled],
    state: &ParticleState,
    frame: HeldFrame,
    tick: f64,
) -> Option<BodyState> {
    let c = coupled
        .iter()
        .find(|c| c.body == frame.body && c.handover)?;
    let i = c.index as usize;
    if i >= state.len() {
        return None;
    }
    let start = frame.start;
    let angular = start.angular as f64 + frame.angular * tick;
    let swept = 0.5 * tick * (start.angular as f64 + angular);
    let centre = state.position[i] - c.arm.as_dvec2();
    let rotation = start.rotation * Rot2::radians(swept as f32);
    let body = BodyState {
        position: centre.as_vec2() - rotation * start.centre_of_mass,
        rotation,
        linear: state.velocity[i].as_vec2(),
        angular: angular as f32,
    };
    (body.position.is_finite() && body.linear.is_finite() && body.angular.is_finite())
        .then_some(body)
}

/// A frame's velocity at the tick's end from its start and the impulses its particles
/// took (and gravity and the engine's acceleration): the momentum the step gave it,
/// not what position corrections left in its particles' velocities.
pub(super) fn frame_motion(
    coupled: &[Coupled],
    frame: HeldFrame,
    (tick, gravity): (f64, DVec2),
) -> (Vec2, f32) {
    let start = frame.start;
    let (mut impulse, mut moment) = (DVec2::ZERO, 0.0);
    for c in coupled
        .iter()
        .filter(|c| c.body == frame.body && c.replaces)
    {
        impulse += c.impulse;
        moment += c.angular;
    }
    let (mass, inertia) = (start.mass as f64, start.inertia as f64);
    let linear = start.linear.as_dvec2() + impulse / mass + (gravity + frame.linear) * tick;
    let turn = if inertia.is_finite() && inertia > 0.0 {
        moment / inertia
    } else {
        0.0
    };
    let angular = start.angular as f64 + turn + frame.angular * tick;
    (linear.as_vec2(), angular as f32)
}

/// The rigid state of `frame`'s particles (its hub and vertices, all simulated), or
/// `None`.
pub(super) fn fit_frame(
    coupled: &[Coupled],
    (x, v, m): &mut (Vec<DVec2>, Vec<DVec2>, Vec<f64>),
    state: &ParticleState,
    frame: HeldFrame,
) -> Option<BodyState> {
    x.clear();
    v.clear();
    m.clear();
    let (mut hub, mut reference) = (None, None);
    let mut farthest = 0.0;
    for c in coupled
        .iter()
        .filter(|c| c.body == frame.body && c.replaces)
    {
        let i = c.index as usize;
        if i >= state.len() {
            return None;
        }
        if c.hub {
            hub = Some(x.len());
        } else {
            let reach = (c.offset - frame.centre_of_mass).length();
            if reach > farthest {
                farthest = reach;
                reference = Some((x.len(), c.offset));
            }
        }
        x.push(state.position[i]);
        v.push(state.velocity[i]);
        m.push(state.mass[i]);
    }
    frame_state((x, v, m), hub?, reference?, frame.centre_of_mass)
}
