//! The motion every stage assumes over a step: each particle moves linearly,
//! `x(τ) = x + τ · dt · v` for τ in [0, 1], so it ends the step at `x + dt · v`. Collision
//! detection sweeps this motion, the constraint solve projects onto its end, and the
//! Integrate stage takes it.

use bevy::math::DVec2;

/// How far a particle moving at `velocity` travels in a step of `dt`.
#[inline]
pub fn displacement(velocity: DVec2, dt: f64) -> DVec2 {
    dt * velocity
}

/// Where a particle at `position` moving at `velocity` ends a step of `dt`.
#[inline]
pub fn end_of_step(position: DVec2, velocity: DVec2, dt: f64) -> DVec2 {
    position + displacement(velocity, dt)
}

/// The displacement of every particle into `out` (cleared first).
pub fn displacements(velocity: &[DVec2], dt: f64, out: &mut Vec<DVec2>) {
    out.clear();
    out.extend(velocity.iter().map(|&v| displacement(v, dt)));
}
