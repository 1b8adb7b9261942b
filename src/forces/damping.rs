//! Mass-proportional damping: `f = −c m v`, a drag that slows every particle at the
//! same rate whatever its mass.

use bevy::math::DVec2;

/// Add `−c m v` to every particle's force.
pub fn add_mass_damping(mass: &[f64], velocity: &[DVec2], force: &mut [DVec2], c: f64) {
    if c == 0.0 {
        return;
    }
    for ((f, &m), &v) in force.iter_mut().zip(mass).zip(velocity) {
        *f -= c * m * v;
    }
}
