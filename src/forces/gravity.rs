//! Gravity: `f = m g`.

use bevy::math::DVec2;

/// Add `m g` to every particle's force.
pub fn add_gravity(mass: &[f64], force: &mut [DVec2], gravity: DVec2) {
    for (f, &m) in force.iter_mut().zip(mass) {
        *f += m * gravity;
    }
}
