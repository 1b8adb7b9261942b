//! Warm starts carried across a renumbering.
//!
//! A row's warm start is keyed by packed indices: the point, and the strand (or, for a
//! corner's second row, the edge) it meets. A topology rebuild may renumber all three —
//! a spawned strand comes first in the packing — and it happens whenever anything is
//! added or removed, and whenever a strand falls asleep or wakes. Dropping the warm
//! starts then cost a pile its support for a step: a cold contact solve meets its rows
//! to the tolerance, not to the weight they carry, so every strand that fell asleep
//! let the awake pile above it sag, and once the sleeping stopped the rows pushed the
//! sagged pile back out of the cushion and threw it upward (the built-in `pile_fine`
//! at 1/300 s gained 410 J that way). So the keys are renamed through the entities
//! they stand for ([`named`] under the old numbering, [`keyed`] under the new), and
//! only the rows whose point, strand or edge is gone lose theirs.

use bevy::ecs::entity::{Entity, EntityHashMap};
use bevy::platform::collections::HashMap;

use super::rows::RowImpulse;
use super::speculative::EDGE_KEY;
use crate::model::Edge;

/// What the packed indices of one topology stand for.
#[derive(Clone, Debug, Default)]
pub struct Numbering {
    /// The topology version recorded (none yet).
    pub version: Option<u64>,
    /// Each packed particle's entity.
    pub particles: Vec<Entity>,
    /// Each strand's entity.
    pub strands: Vec<Entity>,
    /// Each edge's ends (packed).
    pub edges: Vec<(u32, u32)>,
}

impl Numbering {
    /// Record the numbering of topology `version`: `particles`, `strands` and `edges`.
    pub fn record(
        &mut self,
        version: u64,
        particles: &[Entity],
        strands: &[Entity],
        edges: &[Edge],
    ) {
        self.version = Some(version);
        self.particles.clear();
        self.particles.extend_from_slice(particles);
        self.strands.clear();
        self.strands.extend_from_slice(strands);
        self.edges.clear();
        self.edges.extend(edges.iter().map(|e| (e.a, e.b)));
    }
}

/// The new topology's look-ups from entities to indices.
pub struct NewIndices<'a> {
    /// Each particle entity's packed index.
    pub particles: &'a EntityHashMap<u32>,
    /// Each strand's entity, by index.
    pub strands: &'a [Entity],
    /// Every edge.
    pub edges: &'a [Edge],
}

/// What a warm-started row meets, by entity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Partner {
    /// The nearest edge of this strand.
    Strand(Entity),
    /// The edge between these two particles (a corner's second row).
    Edge(Entity, Entity),
}

/// A warm start named by the entities it stands for, as a snapshot keeps it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NamedWarmStart {
    /// The point.
    pub point: Entity,
    /// What it meets.
    pub partner: Partner,
    /// The impulse.
    pub impulse: RowImpulse,
}

/// `warm`'s entries named through `numbering` (those it cannot name are left out).
pub fn named(warm: &[(u32, u32, RowImpulse)], numbering: &Numbering) -> Vec<NamedWarmStart> {
    let particle = |i: u32| numbering.particles.get(i as usize).copied();
    (warm.iter())
        .filter_map(|&(p, key, impulse)| {
            let partner = if key & EDGE_KEY != 0 {
                let &(a, b) = numbering.edges.get((key & !EDGE_KEY) as usize)?;
                Partner::Edge(particle(a)?, particle(b)?)
            } else {
                Partner::Strand(*numbering.strands.get(key as usize)?)
            };
            Some(NamedWarmStart {
                point: particle(p)?,
                partner,
                impulse,
            })
        })
        .collect()
}

/// `named` keyed by the indices of `new`, sorted by key (those it does not hold are
/// left out).
pub fn keyed(named: &[NamedWarmStart], new: &NewIndices) -> Vec<(u32, u32, RowImpulse)> {
    let strand_of: HashMap<Entity, u32> = (new.strands.iter().enumerate())
        .map(|(i, &e)| (e, i as u32))
        .collect();
    let corners = named.iter().any(|w| matches!(w.partner, Partner::Edge(..)));
    let edge_of: HashMap<(u32, u32), u32> = if corners {
        (new.edges.iter().enumerate())
            .map(|(k, e)| ((e.a, e.b), k as u32))
            .collect()
    } else {
        HashMap::default()
    };
    let particle = |e: &Entity| new.particles.get(e).copied();
    let mut warm: Vec<(u32, u32, RowImpulse)> = (named.iter())
        .filter_map(|w| {
            let key = match w.partner {
                Partner::Strand(s) => *strand_of.get(&s)?,
                Partner::Edge(a, b) => EDGE_KEY | edge_of.get(&(particle(&a)?, particle(&b)?))?,
            };
            Some((particle(&w.point)?, key, w.impulse))
        })
        .collect();
    warm.sort_unstable_by_key(|&(p, k, _)| (p, k));
    warm
}

#[cfg(test)]
mod tests {
    use super::*;

    fn impulse(normal: f64) -> RowImpulse {
        RowImpulse {
            normal,
            tangent: 0.0,
        }
    }

    #[test]
    fn keys_follow_their_entities_and_vanish_with_them() {
        let e = |i: u32| Entity::from_raw_u32(i + 1).unwrap();
        // Old: particles e0..e5, strands s10 (edges 0–1, 1–2) and s11 (edges 3–4,
        // 4–5).
        let edges = |pairs: &[(u32, u32)]| -> Vec<Edge> {
            pairs.iter().map(|&(a, b)| Edge::new(a, b, 1.0)).collect()
        };
        let mut old = Numbering::default();
        old.record(
            1,
            &(0..6).map(e).collect::<Vec<_>>(),
            &[e(10), e(11)],
            &edges(&[(0, 1), (1, 2), (3, 4), (4, 5)]),
        );
        let warm = vec![
            (0, 1, impulse(1.0)),            // point e0 on strand s11
            (3, 0, impulse(2.0)),            // point e3 on strand s10
            (4, EDGE_KEY | 1, impulse(3.0)), // point e4 on edge e1–e2
            (2, 1, impulse(4.0)),            // point e2, gone below
        ];
        // New: a strand s12 spawned first (e20, e21), then s11 and s10 in a new order;
        // e2 is gone, so s10's edges are only e0–e1.
        let order = [e(20), e(21), e(3), e(4), e(5), e(0), e(1)];
        let index: EntityHashMap<u32> = (order.iter().enumerate())
            .map(|(i, &entity)| (entity, i as u32))
            .collect();
        let new_edges = edges(&[(0, 1), (2, 3), (3, 4), (5, 6)]);
        let strands = [e(12), e(11), e(10)];
        let warm = keyed(
            &named(&warm, &old),
            &NewIndices {
                particles: &index,
                strands: &strands,
                edges: &new_edges,
            },
        );
        assert_eq!(
            warm.iter()
                .map(|&(p, k, i)| (p, k, i.normal))
                .collect::<Vec<_>>(),
            vec![(2, 2, 2.0), (5, 1, 1.0)],
            "e3 on s10 and e0 on s11; e4's edge e1–e2 and e2's row are gone"
        );
    }

    #[test]
    fn an_unchanged_numbering_keeps_every_warm_start() {
        let e = |i: u32| Entity::from_raw_u32(i + 1).unwrap();
        let particles: Vec<Entity> = (0..4).map(e).collect();
        let edges = vec![Edge::new(0, 1, 1.0), Edge::new(2, 3, 1.0)];
        let mut old = Numbering::default();
        old.record(1, &particles, &[e(10), e(11)], &edges);
        let warm0 = vec![
            (0, 1, impulse(1.0)),
            (1, EDGE_KEY | 1, impulse(2.0)),
            (3, 0, impulse(3.0)),
        ];
        let index: EntityHashMap<u32> = (particles.iter().enumerate())
            .map(|(i, &entity)| (entity, i as u32))
            .collect();
        let warm = keyed(
            &named(&warm0, &old),
            &NewIndices {
                particles: &index,
                strands: &[e(10), e(11)],
                edges: &edges,
            },
        );
        assert_eq!(warm, warm0);
    }
}
