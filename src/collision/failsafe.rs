//! The fail-safe: rigid impact zones (Provot 1997; Bridson, Fedkiw & Anderson 2002).
//!
//! When iterated impulses leave collisions unresolved, the particles involved are
//! merged into zones that move rigidly for the rest of the step, with the zone's
//! linear and angular momentum. Zones that touch merge, and a zone that still collides
//! with itself (a linearly moving rotation is only nearly rigid) drops its rotation and
//! translates. Zones only ever grow or lose their rotation, so the process ends, and a
//! translating zone has no internal motion left to cross with. A zone holding a pinned
//! particle moves with the pinned particles.

use bevy::math::DVec2;

use crate::model::UnionFind;

/// Zone membership and per-zone sums, reused between steps.
#[derive(Clone, Debug, Default)]
pub struct ImpactZones {
    sets: UnionFind,
    translation_only: Vec<bool>,
    members: Vec<u32>,
    in_zone: Vec<bool>,
    mass: Vec<f64>,
    moment: Vec<DVec2>,
    momentum: Vec<DVec2>,
    pinned: Vec<u32>,
    pinned_velocity: Vec<DVec2>,
    angular: Vec<f64>,
    inertia: Vec<f64>,
}

impl ImpactZones {
    /// Every particle in a zone of its own.
    pub fn reset(&mut self, particles: usize) {
        self.sets.reset(particles);
        for flags in [&mut self.translation_only, &mut self.in_zone] {
            flags.clear();
            flags.resize(particles, false);
        }
        self.members.clear();
    }

    /// The zone of particle `i`.
    pub fn zone(&mut self, i: usize) -> usize {
        self.sets.find(i)
    }

    /// Put `a` and `b` in one zone; whether anything changed.
    pub fn join(&mut self, a: usize, b: usize) -> bool {
        for i in [a, b] {
            if !self.in_zone[i] {
                self.in_zone[i] = true;
                self.members.push(i as u32);
            }
        }
        match self.sets.union(a, b) {
            Some((keep, merged)) => {
                self.translation_only[keep] |= self.translation_only[merged];
                true
            }
            None => false,
        }
    }

    /// Make the zone of `i` translate only; whether it rotated before.
    pub fn stop_rotation(&mut self, i: usize) -> bool {
        let z = self.zone(i);
        !std::mem::replace(&mut self.translation_only[z], true)
    }

    /// The particles in any zone.
    pub fn members(&self) -> &[u32] {
        &self.members
    }

    /// Whether each particle is in a zone, by packed index.
    pub fn in_zone(&self) -> &[bool] {
        &self.in_zone
    }

    /// Give every zone's members the zone's rigid velocity.
    pub fn rigidify(
        &mut self,
        position: &[DVec2],
        velocity: &mut [DVec2],
        mass: &[f64],
        inverse_mass: &[f64],
    ) {
        let n = position.len();
        for buffer in [&mut self.mass, &mut self.angular, &mut self.inertia] {
            buffer.clear();
            buffer.resize(n, 0.0);
        }
        for buffer in [
            &mut self.moment,
            &mut self.momentum,
            &mut self.pinned_velocity,
        ] {
            buffer.clear();
            buffer.resize(n, DVec2::ZERO);
        }
        self.pinned.clear();
        self.pinned.resize(n, 0);
        let members = std::mem::take(&mut self.members);
        // First moments: mass, centre of mass, momentum; pinned velocities apart.
        for &i in &members {
            let (i, z) = (i as usize, self.zone(i as usize));
            if inverse_mass[i] == 0.0 {
                self.pinned[z] += 1;
                self.pinned_velocity[z] += velocity[i];
            } else {
                self.mass[z] += mass[i];
                self.moment[z] += mass[i] * position[i];
                self.momentum[z] += mass[i] * velocity[i];
            }
        }
        // Second moments about each zone's centre of mass.
        for &i in &members {
            let (i, z) = (i as usize, self.zone(i as usize));
            if inverse_mass[i] > 0.0 && self.mass[z] > 0.0 {
                let arm = position[i] - self.moment[z] / self.mass[z];
                self.angular[z] +=
                    mass[i] * arm.perp_dot(velocity[i] - self.momentum[z] / self.mass[z]);
                self.inertia[z] += mass[i] * arm.length_squared();
            }
        }
        for &i in &members {
            let (i, z) = (i as usize, self.zone(i as usize));
            if inverse_mass[i] == 0.0 || self.mass[z] == 0.0 {
                continue;
            }
            velocity[i] = if self.pinned[z] > 0 {
                self.pinned_velocity[z] / self.pinned[z] as f64
            } else {
                let centre = self.moment[z] / self.mass[z];
                let linear = self.momentum[z] / self.mass[z];
                let spin = if self.translation_only[z] || self.inertia[z] == 0.0 {
                    0.0
                } else {
                    self.angular[z] / self.inertia[z]
                };
                linear + spin * (position[i] - centre).perp()
            };
        }
        self.members = members;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zone_keeps_its_momentum_and_moves_rigidly() {
        let position = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.0, 2.0),
            DVec2::new(5.0, 5.0),
        ];
        let mass = [1.0, 2.0, 3.0, 1.0];
        let inverse_mass = mass.map(|m| 1.0 / m);
        let mut velocity = [
            DVec2::new(1.0, 0.0),
            DVec2::new(0.0, -1.0),
            DVec2::new(0.5, 0.5),
            DVec2::new(9.0, 9.0),
        ];
        let before = velocity;
        let mut zones = ImpactZones::default();
        zones.reset(4);
        assert!(zones.join(0, 1));
        assert!(zones.join(1, 2));
        assert!(!zones.join(0, 2));
        zones.rigidify(&position, &mut velocity, &mass, &inverse_mass);
        let momentum = |v: &[DVec2]| -> DVec2 { (0..3).map(|i| mass[i] * v[i]).sum() };
        let angular =
            |v: &[DVec2]| -> f64 { (0..3).map(|i| mass[i] * position[i].perp_dot(v[i])).sum() };
        assert!((momentum(&velocity) - momentum(&before)).length() < 1e-14);
        assert!((angular(&velocity) - angular(&before)).abs() < 1e-14);
        // Rigid: no relative velocity along any pair's separation.
        for (i, j) in [(0, 1), (1, 2), (0, 2)] {
            let stretch = (position[j] - position[i]).dot(velocity[j] - velocity[i]);
            assert!(stretch.abs() < 1e-14, "{i}-{j}");
        }
        assert_eq!(velocity[3], before[3], "outside every zone");

        zones.stop_rotation(0);
        zones.rigidify(&position, &mut velocity, &mass, &inverse_mass);
        assert_eq!(velocity[0], velocity[2], "a translating zone");
    }

    #[test]
    fn a_zone_with_a_pinned_particle_moves_with_it() {
        let position = [DVec2::ZERO, DVec2::X];
        let mass = [1.0, 1.0];
        let inverse_mass = [0.0, 1.0];
        let mut velocity = [DVec2::new(0.1, 0.0), DVec2::new(-3.0, 2.0)];
        let mut zones = ImpactZones::default();
        zones.reset(2);
        zones.join(0, 1);
        zones.rigidify(&position, &mut velocity, &mass, &inverse_mass);
        assert_eq!(velocity, [DVec2::new(0.1, 0.0); 2]);
    }
}
