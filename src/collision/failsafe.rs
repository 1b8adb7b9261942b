//! The fail-safe: rigid impact zones (Provot 1997; Bridson, Fedkiw & Anderson 2002),
//! moved by exact rigid motions so that they keep every edge's length.
//!
//! When iterated impulses leave collisions unresolved, the particles involved are
//! merged into zones that move rigidly for the step. A zone takes in whole rigid groups
//! (the constraint islands: every particle joined to it by constrained edges), so that
//! no constrained edge has one end inside a zone and the other outside. Its motion is
//! exact: each member ends the step at `c' + R(θ)(x − c)`, a rotation by the angle
//! `θ = ω dt` and not its linearization `v + ω × r`, so the distance between any two
//! members — every edge of the zone among them — is the same at the end of the step as
//! at its start, to rounding. Zones that touch merge; a zone that still collides with
//! itself (the straight motion of each member is only a chord of its arc) drops its
//! rotation and translates. Zones only ever grow or lose their rotation, so the process
//! ends, and a translating zone has no internal motion left to cross with.
//!
//! A zone takes in with each group the pinned particles the group's edges hang from
//! (its anchors), so that those edges are kept too. A zone holding pinned particles
//! moves as they do — as its anchors do, if it has any, the other pins being only
//! obstacles it met: with one, it translates with it and turns about it with the zone's
//! angular momentum; with several, it follows the rigid motion that best fits theirs
//! (exact when the pins move rigidly together, as walls and a creature's roots do). A
//! zone whose anchored motion still runs into an obstacle is a collision nothing can
//! resolve, and is reported as one.

use bevy::math::DVec2;

use crate::model::{Edge, NO_ISLAND as NO_GROUP, UnionFind};

/// Zone membership and per-zone sums, reused between steps.
#[derive(Clone, Debug, Default)]
pub struct ImpactZones {
    sets: UnionFind,
    translation_only: Vec<bool>,
    members: Vec<u32>,
    in_zone: Vec<bool>,
    group_start: Vec<u32>,
    group_members: Vec<u32>,
    group_joined: Vec<bool>,
    anchor_start: Vec<u32>,
    anchors: Vec<u32>,
    is_anchor: Vec<bool>,
    cursor: Vec<u32>,
    sums: Vec<ZoneSums>,
}

/// What a zone's rigid motion is computed from.
#[derive(Clone, Copy, Debug, Default)]
struct ZoneSums {
    mass: f64,
    moment: DVec2,
    momentum: DVec2,
    pins: u32,
    pin_start: DVec2,
    pin_end: DVec2,
    anchors: u32,
    angular: f64,
    inertia: f64,
    pin_cross: f64,
    pin_dot: f64,
}

/// A zone's rigid motion: members end at `to + R(angle)(x − from)`.
#[derive(Clone, Copy, Debug)]
struct RigidMotion {
    from: DVec2,
    to: DVec2,
    angle: f64,
}

impl ImpactZones {
    /// Every one of `particles` particles in a zone of its own.
    pub fn reset(&mut self, particles: usize) {
        self.sets.reset(particles);
        for flags in [
            &mut self.translation_only,
            &mut self.in_zone,
            &mut self.is_anchor,
        ] {
            flags.clear();
            flags.resize(particles, false);
        }
        self.members.clear();
        self.group_joined.clear();
    }

    /// Learn the rigid groups before zones are joined: `groups` gives each particle's
    /// (its constraint island), [`NO_GROUP`] for none, and the constrained `edges` with
    /// one pinned end (`inverse_mass` 0) hang their group from that pin. Only the
    /// fail-safe needs this, so only it pays for it.
    pub fn prepare_groups(&mut self, groups: &[u32], edges: &[Edge], inverse_mass: &[f64]) {
        // The members of each group, by counting sort.
        let count = groups
            .iter()
            .filter(|&&g| g != NO_GROUP)
            .map(|&g| g as usize + 1)
            .max()
            .unwrap_or(0);
        self.group_start.clear();
        self.group_start.resize(count + 1, 0);
        for &g in groups.iter().filter(|&&g| g != NO_GROUP) {
            self.group_start[g as usize + 1] += 1;
        }
        for g in 0..count {
            self.group_start[g + 1] += self.group_start[g];
        }
        self.group_members.clear();
        self.group_members
            .resize(self.group_start[count] as usize, 0);
        let cursor = &mut self.cursor;
        cursor.clear();
        cursor.extend_from_slice(&self.group_start);
        for (i, &g) in groups.iter().enumerate().filter(|(_, g)| **g != NO_GROUP) {
            self.group_members[cursor[g as usize] as usize] = i as u32;
            cursor[g as usize] += 1;
        }
        self.group_joined.clear();
        self.group_joined.resize(count, false);
        // The pins each group hangs from, by counting sort too.
        let anchor = |e: &Edge| -> Option<(u32, u32)> {
            let (a, b) = (e.a as usize, e.b as usize);
            match (inverse_mass[a] == 0.0, inverse_mass[b] == 0.0) {
                (true, false) if groups[b] != NO_GROUP => Some((groups[b], e.a)),
                (false, true) if groups[a] != NO_GROUP => Some((groups[a], e.b)),
                _ => None,
            }
        };
        self.anchor_start.clear();
        self.anchor_start.resize(count + 1, 0);
        for (g, _) in edges.iter().filter(|e| e.constrained).filter_map(anchor) {
            self.anchor_start[g as usize + 1] += 1;
        }
        for g in 0..count {
            self.anchor_start[g + 1] += self.anchor_start[g];
        }
        self.anchors.clear();
        self.anchors.resize(self.anchor_start[count] as usize, 0);
        let cursor = &mut self.cursor;
        cursor.clear();
        cursor.extend_from_slice(&self.anchor_start);
        for (g, pin) in edges.iter().filter(|e| e.constrained).filter_map(anchor) {
            self.anchors[cursor[g as usize] as usize] = pin;
            cursor[g as usize] += 1;
        }
    }

    /// Put every particle of group `g`, and the pins it hangs from, in the zone of
    /// particle `first` of the group.
    fn take_in_group(&mut self, g: usize, first: usize) {
        self.group_joined[g] = true;
        let members = self.group_start[g] as usize..self.group_start[g + 1] as usize;
        let anchors = self.anchor_start[g] as usize..self.anchor_start[g + 1] as usize;
        for slot in members {
            self.take_in(first, self.group_members[slot] as usize);
        }
        for slot in anchors {
            let pin = self.anchors[slot] as usize;
            self.is_anchor[pin] = true;
            self.take_in(first, pin);
        }
    }

    /// Put `j` in the zone of `first`.
    fn take_in(&mut self, first: usize, j: usize) {
        self.enter(j);
        if let Some((keep, merged)) = self.sets.union(first, j) {
            self.translation_only[keep] |= self.translation_only[merged];
        }
    }

    /// The zone of particle `i`.
    pub fn zone(&mut self, i: usize) -> usize {
        self.sets.find(i)
    }

    fn enter(&mut self, i: usize) {
        if !self.in_zone[i] {
            self.in_zone[i] = true;
            self.members.push(i as u32);
        }
    }

    /// Put `a` and `b`, and the whole rigid groups of each, in one zone; whether
    /// anything changed.
    pub fn join(&mut self, a: usize, b: usize, groups: &[u32]) -> bool {
        let mut changed = false;
        for i in [a, b] {
            changed |= !self.in_zone[i];
            self.enter(i);
            let g = groups[i];
            if g != NO_GROUP && self.group_joined.get(g as usize) == Some(&false) {
                self.take_in_group(g as usize, i);
                changed = true;
            }
        }
        if let Some((keep, merged)) = self.sets.union(a, b) {
            self.translation_only[keep] |= self.translation_only[merged];
            changed = true;
        }
        changed
    }

    /// Put every particle of rigid group `g`, and the pins it hangs from, in one zone.
    pub fn join_group(&mut self, g: u32) {
        let start = self.group_start[g as usize] as usize;
        if start < self.group_start[g as usize + 1] as usize && !self.group_joined[g as usize] {
            let first = self.group_members[start] as usize;
            self.take_in_group(g as usize, first);
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

    /// Give every zone's free members the velocity of the zone's exact rigid motion
    /// over a step of `dt`; pinned members keep theirs.
    pub fn rigidify(
        &mut self,
        position: &[DVec2],
        velocity: &mut [DVec2],
        mass: &[f64],
        inverse_mass: &[f64],
        dt: f64,
    ) {
        let n = position.len();
        self.sums.clear();
        self.sums.resize(n, ZoneSums::default());
        let members = std::mem::take(&mut self.members);
        // Which pins move each zone: its anchors if it has any, else all its pins.
        for &i in &members {
            let (i, z) = (i as usize, self.zone(i as usize));
            if inverse_mass[i] == 0.0 && self.is_anchor[i] {
                self.sums[z].anchors += 1;
            }
        }
        let leads = |sums: &ZoneSums, anchor: bool| sums.anchors == 0 || anchor;
        // First moments: mass, centre of mass, momentum; the leading pins' motion apart.
        for &i in &members {
            let (i, z) = (i as usize, self.zone(i as usize));
            let leading = leads(&self.sums[z], self.is_anchor[i]);
            let s = &mut self.sums[z];
            if inverse_mass[i] == 0.0 {
                if leading {
                    s.pins += 1;
                    s.pin_start += position[i];
                    s.pin_end += position[i] + dt * velocity[i];
                }
            } else {
                s.mass += mass[i];
                s.moment += mass[i] * position[i];
                s.momentum += mass[i] * velocity[i];
            }
        }
        // Second moments: about the centre of mass, or about the pin when there is one;
        // and the leading pins' rotation about their centroid.
        for &i in &members {
            let (i, z) = (i as usize, self.zone(i as usize));
            let s = self.sums[z];
            if inverse_mass[i] == 0.0 {
                if !leads(&s, self.is_anchor[i]) {
                    continue;
                }
                let pins = s.pins as f64;
                let start = position[i] - s.pin_start / pins;
                let end = position[i] + dt * velocity[i] - s.pin_end / pins;
                let sums = &mut self.sums[z];
                sums.pin_cross += start.perp_dot(end);
                sums.pin_dot += start.dot(end);
            } else if s.mass > 0.0 {
                let (centre, linear) = if s.pins == 1 {
                    (s.pin_start, (s.pin_end - s.pin_start) / dt)
                } else {
                    (s.moment / s.mass, s.momentum / s.mass)
                };
                let arm = position[i] - centre;
                let sums = &mut self.sums[z];
                sums.angular += mass[i] * arm.perp_dot(velocity[i] - linear);
                sums.inertia += mass[i] * arm.length_squared();
            }
        }
        for &i in &members {
            let (i, z) = (i as usize, self.zone(i as usize));
            if inverse_mass[i] == 0.0 || self.sums[z].mass == 0.0 {
                continue;
            }
            let motion = self.motion(z, dt);
            let end = motion.to + DVec2::from_angle(motion.angle).rotate(position[i] - motion.from);
            velocity[i] = (end - position[i]) / dt;
        }
        self.members = members;
    }

    /// The rigid motion of zone `z` over a step of `dt`, from its sums.
    fn motion(&self, z: usize, dt: f64) -> RigidMotion {
        let s = &self.sums[z];
        let turns = !self.translation_only[z];
        match s.pins {
            0 => {
                let centre = s.moment / s.mass;
                let spin = if turns && s.inertia > 0.0 {
                    s.angular / s.inertia
                } else {
                    0.0
                };
                RigidMotion {
                    from: centre,
                    to: centre + dt * s.momentum / s.mass,
                    angle: spin * dt,
                }
            }
            1 => {
                let spin = if turns && s.inertia > 0.0 {
                    s.angular / s.inertia
                } else {
                    0.0
                };
                RigidMotion {
                    from: s.pin_start,
                    to: s.pin_end,
                    angle: spin * dt,
                }
            }
            pins => {
                let pins = pins as f64;
                RigidMotion {
                    from: s.pin_start / pins,
                    to: s.pin_end / pins,
                    // The rotation that best carries the pins' start onto their end
                    // (two-dimensional Procrustes); exact when they move rigidly.
                    angle: s.pin_cross.atan2(s.pin_dot),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn no_groups(n: usize) -> Vec<u32> {
        vec![NO_GROUP; n]
    }

    #[test]
    fn a_zone_keeps_its_momentum_and_every_distance_exactly() {
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
        let groups = no_groups(4);
        let mut zones = ImpactZones::default();
        zones.reset(groups.len());
        zones.prepare_groups(&groups, &[], &vec![1.0; groups.len()]);
        assert!(zones.join(0, 1, &groups));
        assert!(zones.join(1, 2, &groups));
        assert!(!zones.join(0, 2, &groups));
        // A large step: a tenth of a turn, where the linearized rotation would change
        // distances by half a percent.
        let dt = 0.1;
        zones.rigidify(&position, &mut velocity, &mass, &inverse_mass, dt);
        let momentum = |v: &[DVec2]| -> DVec2 { (0..3).map(|i| mass[i] * v[i]).sum() };
        assert!((momentum(&velocity) - momentum(&before)).length() < 1e-14);
        let end = |i: usize| position[i] + dt * velocity[i];
        for (i, j) in [(0, 1), (1, 2), (0, 2)] {
            let (start, finish) = (position[i].distance(position[j]), end(i).distance(end(j)));
            assert!(((finish - start) / start).abs() < 1e-14, "{i}-{j}");
        }
        // It turned, by the angular momentum's angle.
        let turned = (position[1] - position[0]).angle_to(end(1) - end(0));
        assert!(turned.abs() > 0.01, "{turned}");
        assert_eq!(velocity[3], before[3], "outside every zone");

        zones.stop_rotation(0);
        zones.rigidify(&position, &mut velocity, &mass, &inverse_mass, dt);
        assert!(
            (velocity[0] - velocity[2]).length() < 1e-15,
            "a translating zone"
        );
    }

    #[test]
    fn a_zone_takes_in_whole_islands() {
        // Particles 0–3 one island, 4–5 another, 6 none: a contact between 1 and 4
        // puts all six in one zone, which keeps both islands' edges exact.
        let groups = [0, 0, 0, 0, 1, 1, NO_GROUP];
        let position: Vec<DVec2> = (0..7).map(|i| DVec2::new(0.1 * i as f64, 0.0)).collect();
        let mut velocity: Vec<DVec2> = (0..7)
            .map(|i| DVec2::new(0.0, if i < 4 { 3.0 } else { -3.0 }) + 0.5 * DVec2::X)
            .collect();
        let mass = [1.0; 7];
        let mut zones = ImpactZones::default();
        zones.reset(groups.len());
        zones.prepare_groups(&groups, &[], &vec![1.0; groups.len()]);
        zones.join(1, 4, &groups);
        assert_eq!(zones.members().len(), 6);
        assert!(!zones.in_zone()[6]);
        zones.rigidify(&position, &mut velocity, &mass, &[1.0; 7], 0.05);
        let end = |i: usize| position[i] + 0.05 * velocity[i];
        for i in 0..5 {
            let (start, finish) = (
                position[i].distance(position[i + 1]),
                end(i).distance(end(i + 1)),
            );
            assert!(((finish - start) / start).abs() < 1e-12, "edge {i}");
        }
    }

    #[test]
    fn a_zone_with_pins_follows_them() {
        // One pin, moving: the zone translates with it and turns about it.
        let position = [DVec2::ZERO, DVec2::X];
        let mass = [1.0, 1.0];
        let mut velocity = [DVec2::new(0.1, 0.0), DVec2::new(-3.0, 2.0)];
        let groups = no_groups(2);
        let mut zones = ImpactZones::default();
        zones.reset(groups.len());
        zones.prepare_groups(&groups, &[], &vec![1.0; groups.len()]);
        zones.join(0, 1, &groups);
        let dt = 0.01;
        zones.rigidify(&position, &mut velocity, &mass, &[0.0, 1.0], dt);
        assert_eq!(
            velocity[0],
            DVec2::new(0.1, 0.0),
            "the pin keeps its motion"
        );
        let end = |i: usize| position[i] + dt * velocity[i];
        assert!((end(0).distance(end(1)) - 1.0).abs() < 1e-14);
        // Two pins standing still (a wall): the zone stops.
        let position = [DVec2::ZERO, DVec2::X, DVec2::new(0.5, 0.1)];
        let mut velocity = [DVec2::ZERO, DVec2::ZERO, DVec2::new(0.0, -4.0)];
        let groups = no_groups(3);
        zones.reset(groups.len());
        zones.prepare_groups(&groups, &[], &vec![1.0; groups.len()]);
        zones.join(2, 0, &groups);
        zones.join(2, 1, &groups);
        zones.rigidify(&position, &mut velocity, &[1.0; 3], &[0.0, 0.0, 1.0], dt);
        assert!(velocity[2].length() < 1e-15, "{:?}", velocity[2]);
    }
}
