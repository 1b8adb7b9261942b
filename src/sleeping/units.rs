//! What sleeps and wakes together, and when a unit has rested long enough.
//!
//! A *unit* is a set of particles that must share one state: the particles of strands
//! joined by shared particles (a tree, a graph, hairs on one root), or a loose particle
//! alone. A wall's particles belong to no unit: they never move on their own. A unit
//! goes to sleep once it has rested for the sleep time and so has every awake unit it
//! touches, so that nothing still settling is left pushing on a body that no longer
//! answers. Waking is per unit: a strand something touches wakes, its sleeping
//! neighbours hold still until something moving reaches them too.

use bevy::math::DVec2;

use crate::model::Edge;
use crate::model::union_find::UnionFind;

/// No unit: a wall's particle.
pub const NO_UNIT: u32 = u32::MAX;

/// The units of a topology: for each packed particle its unit (or [`NO_UNIT`]), and the
/// particles of each unit together.
#[derive(Clone, Debug, Default)]
pub struct Units {
    /// The unit of each packed particle.
    pub of: Vec<u32>,
    /// Where each unit's particles start in `members` (one more entry than units).
    pub start: Vec<u32>,
    /// The particles of every unit, unit by unit, each in packed order.
    pub members: Vec<u32>,
}

impl Units {
    /// How many units there are.
    pub fn len(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The particles of unit `u`.
    pub fn particles(&self, u: usize) -> &[u32] {
        &self.members[self.start[u] as usize..self.start[u + 1] as usize]
    }

    /// Find the units of `count` particles joined by `edges`; particles `solid` (walls,
    /// bodies) belong to none. Units are numbered by their first particle.
    pub fn find(&mut self, count: usize, edges: &[Edge], solid: &[bool], sets: &mut UnionFind) {
        sets.reset(count);
        for e in edges.iter().filter(|e| !e.solid) {
            sets.union(e.a as usize, e.b as usize);
        }
        self.of.clear();
        self.of.resize(count, NO_UNIT);
        // Each set's number, given when its first particle is met.
        let mut label = vec![NO_UNIT; count];
        let mut sizes: Vec<u32> = Vec::new();
        for i in 0..count {
            if solid.get(i).copied().unwrap_or(false) {
                continue;
            }
            let root = sets.find(i);
            if label[root] == NO_UNIT {
                label[root] = sizes.len() as u32;
                sizes.push(0);
            }
            self.of[i] = label[root];
            sizes[label[root] as usize] += 1;
        }
        let units = sizes.len();
        self.start.clear();
        self.start.push(0);
        for size in &sizes {
            let last = *self.start.last().expect("a start");
            self.start.push(last + size);
        }
        self.members.clear();
        self.members
            .resize(*self.start.last().expect("a start") as usize, 0);
        let mut fill: Vec<u32> = self.start[..units].to_vec();
        for (i, &u) in self.of.iter().enumerate() {
            if u != NO_UNIT {
                self.members[fill[u as usize] as usize] = i as u32;
                fill[u as usize] += 1;
            }
        }
    }
}

/// Each awake unit's rest: `rested[u]` grows by `tick` while every particle of the
/// unit stays within `drift` of its anchor (where it was when the rest began); a unit
/// that strays further starts again from zero, anchored where it is now. `strayed[u]`
/// is how far its particles are from their anchors (at most). A drift over the whole
/// rest, not a speed at one instant: strands held in a pile tremble by a few
/// centimetres a second about positions that move by less than a millimetre.
#[allow(clippy::too_many_arguments)]
pub fn rest(
    units: &Units,
    position: &[DVec2],
    asleep: &[bool],
    drift: f64,
    tick: f64,
    anchors: &mut [DVec2],
    rested: &mut [f64],
    strayed: &mut [f64],
) {
    for u in (0..units.len()).filter(|&u| !asleep[u]) {
        let range = units.start[u] as usize..units.start[u + 1] as usize;
        let members = &units.members[range.clone()];
        let anchors = &mut anchors[range];
        let farthest = members
            .iter()
            .zip(anchors.iter())
            .map(|(&i, a)| position[i as usize].distance_squared(*a))
            .fold(0.0, f64::max)
            .sqrt();
        if farthest > drift {
            for (&i, a) in members.iter().zip(anchors.iter_mut()) {
                *a = position[i as usize];
            }
            rested[u] = 0.0;
            strayed[u] = 0.0;
        } else {
            rested[u] += tick;
            strayed[u] = farthest;
        }
    }
}

/// Whether a unit that has rested `rested` seconds and strayed `strayed` from its
/// anchors is still on the move: its mean speed since its rest began is over `speed`
/// (or its rest has just begun). A falling strand moves from its first tick; one
/// trembling in a pile does not.
pub fn on_the_move(rested: f64, strayed: f64, speed: f64) -> bool {
    rested == 0.0 || strayed > speed * rested
}

/// The units to put to sleep now: every awake unit that is not `restless`, has rested
/// (`rested[u]` seconds) at least `time`, and touches (by `contacts`, pairs of units)
/// no awake unit that has not. Appends them to `sleepers` in unit order; `blocked` is
/// scratch. A neighbourhood, not the whole contact group: a pile fed from above
/// sleeps from the bottom up while strands keep landing on its top, each layer once
/// the one over it rests too.
pub fn units_to_sleep(
    asleep: &[bool],
    restless: &[bool],
    rested: &[f64],
    time: f64,
    contacts: &[(u32, u32)],
    blocked: &mut Vec<bool>,
    sleepers: &mut Vec<u32>,
) {
    let n = asleep.len();
    let ready = |u: usize| !restless[u] && rested[u] >= time;
    blocked.clear();
    blocked.resize(n, false);
    for &(a, b) in contacts {
        let (a, b) = (a as usize, b as usize);
        if a < n && b < n && !asleep[a] && !asleep[b] {
            blocked[a] |= !ready(b);
            blocked[b] |= !ready(a);
        }
    }
    for u in (0..n).filter(|&u| !asleep[u] && ready(u) && !blocked[u]) {
        sleepers.push(u as u32);
    }
}

/// The sleeping units something presses on: touched (by `contacts`) by an awake unit
/// that has not rested `time` — still settling, creeping or pushed, at whatever speed.
/// Marks them in `pressed`. A unit at rest on a sleeping one presses on nothing, so a
/// touch wakes only a neighbourhood, not a whole pile.
pub fn pressed_units(
    asleep: &[bool],
    rested: &[f64],
    time: f64,
    contacts: &[(u32, u32)],
    pressed: &mut Vec<bool>,
) {
    let n = asleep.len();
    pressed.clear();
    pressed.resize(n, false);
    for &(a, b) in contacts {
        let (a, b) = (a as usize, b as usize);
        if a < n && b < n && asleep[a] != asleep[b] {
            let (awake, sleeping) = if asleep[a] { (b, a) } else { (a, b) };
            pressed[sleeping] |= rested[awake] < time;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(a: u32, b: u32, solid: bool) -> Edge {
        Edge {
            a,
            b,
            rest_length: 1.0,
            strand: 0,
            is_static: false,
            constrained: true,
            spring: false,
            stiffness: 0.0,
            damping: 0.0,
            solid,
        }
    }

    #[test]
    fn strands_sharing_a_particle_are_one_unit_and_walls_none() {
        // 0-1-2 and 2-3 share 2; 4 is loose; 5-6 is a wall.
        let edges = [
            edge(0, 1, false),
            edge(1, 2, false),
            edge(3, 2, false),
            edge(5, 6, true),
        ];
        let solid = [false, false, false, false, false, true, true];
        let mut units = Units::default();
        units.find(7, &edges, &solid, &mut UnionFind::new(0));
        assert_eq!(units.len(), 2);
        assert_eq!(units.of, vec![0, 0, 0, 0, 1, NO_UNIT, NO_UNIT]);
        assert_eq!(units.particles(0), &[0, 1, 2, 3]);
        assert_eq!(units.particles(1), &[4]);
    }

    #[test]
    fn units_are_numbered_by_their_first_particle() {
        // 0 joins 3 (a later root), 1-2 between.
        let edges = [edge(3, 0, false), edge(1, 2, false)];
        let mut units = Units::default();
        units.find(4, &edges, &[false; 4], &mut UnionFind::new(0));
        assert_eq!(units.of, vec![0, 1, 1, 0]);
    }

    #[test]
    fn a_unit_sleeps_only_when_its_awake_neighbours_have_rested() {
        // Units 0-1 touch, 2 alone, 3 touches 1 but is asleep, 4 restless.
        let asleep = [false, false, false, true, false];
        let restless = [false, false, false, false, true];
        let rested = [1.0, 0.2, 1.0, 0.0, 1.0];
        let contacts = [(0, 1), (1, 3)];
        let mut sleepers = Vec::new();
        units_to_sleep(
            &asleep,
            &restless,
            &rested,
            0.5,
            &contacts,
            &mut Vec::new(),
            &mut sleepers,
        );
        assert_eq!(sleepers, vec![2]);
        let rested = [1.0, 0.6, 1.0, 0.0, 1.0];
        sleepers.clear();
        units_to_sleep(
            &asleep,
            &restless,
            &rested,
            0.5,
            &contacts,
            &mut Vec::new(),
            &mut sleepers,
        );
        assert_eq!(sleepers, vec![0, 1, 2]);
    }

    #[test]
    fn a_trembling_unit_rests_and_a_drifting_one_does_not() {
        let edges = [edge(0, 1, false)];
        let mut units = Units::default();
        units.find(3, &edges, &[false; 3], &mut UnionFind::new(0));
        let start = [DVec2::ZERO, DVec2::X, DVec2::Y];
        let mut anchors = start.to_vec();
        let mut rested = vec![0.0; 2];
        let mut strayed = vec![0.0; 2];
        for k in 0..10 {
            // Unit 0 trembles by 1 mm about its start, unit 1 drifts 1 mm a tick.
            let shake = DVec2::new(if k % 2 == 0 { 1e-3 } else { -1e-3 }, 0.0);
            let drift = DVec2::new(1e-3 * f64::from(k + 1), 0.0);
            let position = [start[0] + shake, start[1] + shake, start[2] + drift];
            rest(
                &units,
                &position,
                &[false, false],
                5e-3,
                0.1,
                &mut anchors,
                &mut rested,
                &mut strayed,
            );
        }
        assert!((rested[0] - 1.0).abs() < 1e-12);
        // Past 5 mm at the sixth tick: anchored again, four ticks since.
        assert!((rested[1] - 0.4).abs() < 1e-12, "{}", rested[1]);
        // Trembling, it is not on the move; drifting 1 mm a tick (1 cm/s), it is.
        assert!(!on_the_move(rested[0], strayed[0], 5e-3));
        assert!(on_the_move(rested[1], strayed[1], 5e-3));
    }

    #[test]
    fn only_an_unrested_awake_unit_presses_on_a_sleeping_one() {
        // Units 0 and 1 asleep, 2 awake and settling, 3 awake and rested.
        let asleep = [true, true, false, false];
        let rested = [0.0, 0.0, 0.4, 1.5];
        let mut pressed = Vec::new();
        pressed_units(
            &asleep,
            &rested,
            1.0,
            &[(0, 2), (1, 3), (2, 3)],
            &mut pressed,
        );
        assert_eq!(pressed, [true, false, false, false]);
        // Two sleeping units touching do not press on each other.
        pressed_units(&asleep, &rested, 1.0, &[(0, 1)], &mut pressed);
        assert_eq!(pressed, [false; 4]);
    }
}
