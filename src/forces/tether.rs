//! Tethers: a damped spring from a particle to a point, the force of a mouse drag or a
//! game's grab.

use bevy::math::DVec2;

/// `f = k (target − x) − c v` on a particle at `x` moving at `v`.
pub fn tether_force(target: DVec2, stiffness: f64, damping: f64, x: DVec2, v: DVec2) -> DVec2 {
    stiffness * (target - x) - damping * v
}
