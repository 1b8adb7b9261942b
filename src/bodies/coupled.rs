//! What the coupling keeps of each particle coupled to a body this tick, and what it
//! reads of an anchored particle: shared by the exchange (the coupling module) and the
//! hand-over (the carry module), which both import it.

use bevy::math::DVec2;
use bevy::prelude::*;

use super::anchor::BodyAnchor;
use super::truss::{OutlineVertex, Rigged};
use crate::world::particle::{Kinematic, Velocity};
use crate::world::strand::StrandOf;

/// One particle coupled to a dynamic body this tick.
#[derive(Clone, Copy, Debug)]
pub(super) struct Coupled {
    pub(super) particle: Entity,
    pub(super) body: Entity,
    /// Packed index, `u32::MAX` until the gather (or if it is not simulated).
    pub(super) index: u32,
    /// The body's effective mass at the particle.
    pub(super) body_mass: f64,
    /// Whether the particle's own mass is replaced (an outline vertex) or added to.
    pub(super) replaces: bool,
    /// The particle's mass in the solve.
    pub(super) total_mass: f64,
    /// The arm from the body's centre of mass at the tick's start (a lone anchor's
    /// torque arm).
    pub(super) arm: Vec2,
    /// Constraint and contact impulse on the particle so far this tick.
    pub(super) impulse: DVec2,
    /// Its angular impulse about the body's centre of mass so far this tick.
    pub(super) angular: f64,
    /// Its point in the body's frame.
    pub(super) offset: Vec2,
    /// Whether it is the frame's centre.
    pub(super) hub: bool,
    /// Whether it is a body's one lone anchor, carrying the body's whole mass: the body
    /// is handed over through it.
    pub(super) handover: bool,
}

/// What the coupling reads and writes of an anchored particle.
pub(super) type AnchorData = (
    Entity,
    &'static BodyAnchor,
    &'static mut Velocity,
    Has<Kinematic>,
    Option<&'static OutlineVertex>,
    Option<&'static Rigged>,
    Option<&'static StrandOf>,
);
