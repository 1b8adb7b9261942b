//! Topology: which particles are simulated, in which packed order, and the edges and
//! bending elements between them.
//!
//! Rebuilt only when something structural changes — a particle or strand added or
//! removed, a pin toggled, a strand edited — never rediscovered every step. The
//! rebuild is also where components edited at run time are validated, with the rules
//! of [`crate::model::validate`]: bad particles and strands are left out with a message
//! in [`InputProblems`], and strands that reference despawned particles are split
//! around the gap.

use std::ops::Range;

use bevy::ecs::entity::EntityHashMap;
use bevy::prelude::*;

use crate::model::validate::{StrandError, check_particle, check_strand_shape};
use crate::model::{Bend, Edge, NO_ISLAND, bend_count};
use crate::world::config::StrandsConfig;
use crate::world::hooks::{SpawnOrder, TopologyDirty};
use crate::world::particle::{
    Frozen, Kinematic, Mass, Particle, Pinned, Position, Sleeping, SolverIndex, Velocity,
};
use crate::world::problems::InputProblems;
use crate::world::state::ParticleState;
use crate::world::strand::{Strand, StrandKind, StrandMaterial, StrandOf};

/// A simulated strand.
#[derive(Clone, Debug, PartialEq)]
pub struct StrandRecord {
    /// The strand entity.
    pub entity: Entity,
    /// What it represents.
    pub kind: StrandKind,
    /// Its edges in [`Topology::edges`].
    pub edges: Range<usize>,
    /// Whether it is a loop.
    pub closed: bool,
}

/// The simulated structure, rebuilt on structural change.
#[derive(Resource, Default, Debug)]
pub struct Topology {
    /// Incremented by every rebuild; caches derived from the topology compare it.
    pub version: u64,
    /// Packed index of every simulated particle.
    pub index: EntityHashMap<u32>,
    /// Whether each packed particle is pinned.
    pub pinned: Vec<bool>,
    /// Whether each packed particle is a vertex of a wall or a collider's body (a
    /// `StrandKind::Wall` strand): such a point never meets another wall's edges.
    pub solid: Vec<bool>,
    /// The solved constraint island of each packed particle, [`NO_ISLAND`] for none;
    /// set by the constraint plugin after each rebuild. A collision fail-safe zone
    /// takes in whole islands.
    pub island: Vec<u32>,
    /// All edges, strand by strand.
    pub edges: Vec<Edge>,
    /// All bending elements.
    pub bends: Vec<Bend>,
    /// All simulated strands.
    pub strands: Vec<StrandRecord>,
    /// The default material the elements were built with.
    default_material: Option<StrandMaterial>,
}

impl Topology {
    /// Number of edges that are not static.
    pub fn dynamic_edge_count(&self) -> usize {
        self.edges.iter().filter(|e| !e.is_static).count()
    }
}

type EditedStrand = Or<(Changed<Strand>, Changed<StrandMaterial>)>;

/// Mark the topology dirty when a strand was edited in place.
pub fn detect_strand_edits(
    topology: Res<Topology>,
    mut dirty: ResMut<TopologyDirty>,
    config: Res<StrandsConfig>,
    edited: Query<(), EditedStrand>,
) {
    if !edited.is_empty() || topology.default_material != Some(config.material) {
        dirty.mark();
    }
}

/// Run condition: a rebuild is pending.
pub fn topology_dirty(dirty: Res<TopologyDirty>) -> bool {
    dirty.0
}

/// Rebuild the topology and re-index the particles.
pub fn rebuild_topology(world: &mut World) {
    split_strands_with_missing_particles(world);

    let default_material = world.resource::<StrandsConfig>().material;
    let mut problems = world.remove_resource::<InputProblems>().unwrap_or_default();

    // Particles that can be simulated, and whether each has infinite mass (pinned,
    // kinematic, frozen or asleep).
    let mut particles = world.query_filtered::<(
        Entity,
        &Position,
        &Velocity,
        &Mass,
        Has<Pinned>,
        Has<Kinematic>,
        Has<Frozen>,
        Has<Sleeping>,
    ), With<Particle>>();
    let mut valid: EntityHashMap<bool> = EntityHashMap::default();
    for (entity, position, velocity, mass, pinned, kinematic, frozen, sleeping) in
        particles.iter(world)
    {
        let pinned = pinned || kinematic || frozen || sleeping;
        match check_particle(position.0, velocity.0, mass.0, pinned) {
            Err(problem) => problems.report(entity, format!("particle left out: {problem}")),
            Ok(()) => {
                valid.insert(entity, pinned);
            }
        }
    }

    let mut strand_query = world.query::<(
        Entity,
        &Strand,
        Option<&StrandMaterial>,
        Option<&StrandKind>,
    )>();
    let mut strands: Vec<(Entity, &Strand, StrandMaterial, StrandKind)> = strand_query
        .iter(world)
        .filter_map(
            |(entity, strand, material, kind)| match check_strand(strand, &valid) {
                Err(problem) => {
                    problems.report(entity, format!("strand left out: {problem}"));
                    None
                }
                Ok(()) => Some((
                    entity,
                    strand,
                    material.copied().unwrap_or(default_material),
                    kind.copied().unwrap_or_default(),
                )),
            },
        )
        .collect();
    let no_order = SpawnOrder::default();
    let spawn_order = world.get_resource::<SpawnOrder>().unwrap_or(&no_order);
    strands.sort_by_cached_key(|(entity, ..)| spawn_order.strand_key(*entity));

    // Packed order: strand by strand along each strand, then loose particles; a strand
    // or particle past the caps is left out, its particles with it.
    let (max_particles, max_edges) = {
        let config = world.resource::<StrandsConfig>();
        (config.max_particles, config.max_edges)
    };
    let mut order: Vec<Entity> = Vec::with_capacity(valid.len().min(max_particles));
    let mut index: EntityHashMap<u32> = EntityHashMap::default();
    let mut left_out: EntityHashMap<()> = EntityHashMap::default();
    let mut edge_total = 0usize;
    strands.retain(|(entity, strand, ..)| {
        let new = strand
            .particles
            .iter()
            .filter(|p| !index.contains_key(*p))
            .count();
        let edges = strand.rest_lengths.len();
        if order.len() + new > max_particles || edge_total + edges > max_edges {
            problems.report(
                *entity,
                format!(
                    "strand left out: with its {} particles and {edges} edges the world \
                     would pass max_particles {max_particles} or max_edges {max_edges}",
                    strand.particles.len()
                ),
            );
            left_out.extend(strand.particles.iter().map(|&p| (p, ())));
            return false;
        }
        edge_total += edges;
        for &p in &strand.particles {
            index.entry(p).or_insert_with(|| {
                order.push(p);
                (order.len() - 1) as u32
            });
        }
        true
    });
    let mut loose: Vec<Entity> = valid
        .keys()
        .copied()
        .filter(|p| !index.contains_key(p) && !left_out.contains_key(p))
        .collect();
    loose.sort_by_cached_key(|p| spawn_order.particle_key(*p));
    let room = max_particles - order.len();
    if let Some(&first) = loose.get(room) {
        problems.report(
            first,
            format!(
                "{} loose particles left out: the world would pass max_particles {max_particles}",
                loose.len() - room
            ),
        );
    }
    for p in loose.into_iter().take(room) {
        index.insert(p, order.len() as u32);
        order.push(p);
    }

    let mut edges = Vec::new();
    let mut bends = Vec::new();
    let mut records = Vec::with_capacity(strands.len());
    for (strand_index, (entity, strand, material, kind)) in strands.iter().enumerate() {
        let first_edge = edges.len();
        let packed: Vec<u32> = strand.particles.iter().map(|p| index[p]).collect();
        let pinned = |i: u32| valid[&order[i as usize]];
        let n = packed.len();
        for (k, &rest_length) in strand.rest_lengths.iter().enumerate() {
            let (a, b) = (packed[k], packed[(k + 1) % n]);
            let is_static = pinned(a) && pinned(b);
            edges.push(Edge {
                a,
                b,
                rest_length,
                strand: strand_index as u32,
                is_static,
                constrained: false,
                spring: !is_static && material.stretch_stiffness > 0.0,
                stiffness: material.stretch_stiffness,
                damping: material.stretch_damping,
                solid: *kind == StrandKind::Wall,
            });
        }
        let bendable = material.bending_stiffness > 0.0 || material.bending_damping > 0.0;
        let bending_vertices = if bendable {
            bend_count(n, strand.closed)
        } else {
            0
        };
        for j in 0..bending_vertices {
            let s = if strand.closed { j } else { j + 1 };
            let prev = (s + n - 1) % n;
            let (a, sv, b) = (packed[prev], packed[s], packed[(s + 1) % n]);
            if pinned(a) && pinned(sv) && pinned(b) {
                continue;
            }
            // Edge v joins vertices v and v + 1, so the edges at s are prev and s.
            let voronoi = 0.5 * (strand.rest_lengths[prev] + strand.rest_lengths[s]);
            bends.push(Bend {
                a,
                s: sv,
                b,
                rest_angle: strand.rest_angles.get(j).copied().unwrap_or(0.0),
                stiffness: material.bending_stiffness / voronoi,
                damping: material.bending_damping,
                rest_lengths: [strand.rest_lengths[prev], strand.rest_lengths[s]],
            });
        }
        records.push(StrandRecord {
            entity: *entity,
            kind: *kind,
            edges: first_edge..edges.len(),
            closed: strand.closed,
        });
    }

    let mut solver_indices = world.query_filtered::<(Entity, &mut SolverIndex), With<Particle>>();
    for (entity, mut solver_index) in solver_indices.iter_mut(world) {
        let new = index
            .get(&entity)
            .map_or(SolverIndex::NONE, |&i| SolverIndex(i));
        solver_index.set_if_neq(new);
    }
    let pinned: Vec<bool> = order.iter().map(|e| valid[e]).collect();
    let topology_len = pinned.len();
    let mut solid = vec![false; topology_len];
    for e in edges.iter().filter(|e| e.solid) {
        solid[e.a as usize] = true;
        solid[e.b as usize] = true;
    }
    world.resource_mut::<ParticleState>().resize(order);
    world.insert_resource(problems);

    let mut topology = world.resource_mut::<Topology>();
    topology.version += 1;
    topology.index = index;
    topology.island.clear();
    topology.island.resize(topology_len, NO_ISLAND);
    topology.pinned = pinned;
    topology.solid = solid;
    topology.edges = edges;
    topology.bends = bends;
    topology.strands = records;
    topology.default_material = Some(default_material);
    world.resource_mut::<TopologyDirty>().0 = false;
}

/// Check a strand component with the rules the builder applies, and that each of its
/// vertices is a particle that can be simulated (`valid`) and no edge joins a particle
/// to itself.
fn check_strand(strand: &Strand, valid: &EntityHashMap<bool>) -> Result<(), StrandError> {
    let n = strand.particles.len();
    check_strand_shape(n, strand.closed, &strand.rest_lengths, &strand.rest_angles)?;
    if let Some(index) = strand.particles.iter().position(|p| !valid.contains_key(p)) {
        return Err(StrandError::NotSimulated { index });
    }
    if let Some(edge) = (0..strand.edge_count()).find(|&k| {
        let (a, b) = strand.edge(k);
        a == b
    }) {
        return Err(StrandError::SelfEdge { edge });
    }
    Ok(())
}

/// Split every strand that lists a despawned particle into the runs of particles that
/// still exist, so that no strand is left referencing a dead entity.
fn split_strands_with_missing_particles(world: &mut World) {
    let mut strands = world.query::<(Entity, &Strand)>();
    let broken: Vec<(Entity, Vec<Entity>)> = strands
        .iter(world)
        .filter_map(|(entity, strand)| {
            let missing: Vec<Entity> = strand
                .particles
                .iter()
                .copied()
                .filter(|&p| world.get_entity(p).is_err())
                .collect();
            (!missing.is_empty()).then_some((entity, missing))
        })
        .collect();
    for (entity, missing) in broken {
        let pieces = split_strand(world, entity, |p| !missing.contains(&p));
        let message = format!(
            "strand referenced despawned particle(s) {missing:?}; split into {pieces} strand(s)"
        );
        world
            .get_resource_or_insert_with(InputProblems::default)
            .report(entity, message);
    }
}

/// Split strand `entity` into the runs of its particles for which `keep` holds: the
/// first run stays on `entity`, the others become new strands (with the same kind and
/// material, owning their particles). With no run of two particles left, the strand is
/// despawned and the particles it owned that are kept outlive it. Returns the number of
/// strands left.
pub fn split_strand(world: &mut World, entity: Entity, keep: impl Fn(Entity) -> bool) -> usize {
    let Some(strand) = world.get::<Strand>(entity).cloned() else {
        return 0;
    };
    let pieces = split_around(&strand, &keep);
    replace_with_pieces(world, entity, &strand, pieces, keep)
}

/// Cut edge `edge` of strand `entity` (see [`cut_pieces`]). Returns the number of
/// strands left, or `None` if there is no such strand or edge.
pub fn cut_strand(world: &mut World, entity: Entity, edge: usize) -> Option<usize> {
    let strand = world.get::<Strand>(entity)?.clone();
    if edge >= strand.edge_count() {
        return None;
    }
    let pieces = cut_pieces(&strand, edge);
    Some(replace_with_pieces(world, entity, &strand, pieces, |_| {
        true
    }))
}

/// Put `pieces` in the place of strand `entity`: the first stays on `entity`, the
/// others become new strands with its kind and material, owning their particles; with
/// no piece the strand is despawned, and the particles it owned for which `keep`
/// holds outlive it, loose.
fn replace_with_pieces(
    world: &mut World,
    entity: Entity,
    strand: &Strand,
    pieces: Vec<Strand>,
    keep: impl Fn(Entity) -> bool,
) -> usize {
    let kind = world.get::<StrandKind>(entity).copied();
    let material = world.get::<StrandMaterial>(entity).copied();
    let owned_by = |world: &World, p: Entity| {
        world
            .get::<StrandOf>(p)
            .is_some_and(|owner| owner.0 == entity)
    };
    // Particles in no piece are freed first, so that despawning the strand (which
    // takes the particles it owns) does not take them.
    let in_pieces: Vec<Entity> = pieces
        .iter()
        .flat_map(|p| p.particles.iter().copied())
        .collect();
    for &p in &strand.particles {
        if keep(p) && !in_pieces.contains(&p) && world.get_entity(p).is_ok() && owned_by(world, p) {
            world.entity_mut(p).remove::<StrandOf>();
        }
    }
    let Some((first, rest)) = pieces.split_first() else {
        world.entity_mut(entity).despawn();
        return 0;
    };
    for piece in rest {
        let mut spawned = world.spawn((piece.clone(), kind.unwrap_or_default()));
        if let Some(material) = material {
            spawned.insert(material);
        }
        let new = spawned.id();
        for &p in &piece.particles {
            if owned_by(world, p) {
                world.entity_mut(p).insert(StrandOf(new));
            }
        }
    }
    world.entity_mut(entity).insert(first.clone());
    pieces.len()
}

/// The runs of consecutive vertices for which `keep` holds, as open strands of at
/// least two particles, with their rest lengths and rest angles.
pub fn split_around(strand: &Strand, keep: impl Fn(Entity) -> bool) -> Vec<Strand> {
    let n = strand.particles.len();
    let kept: Vec<bool> = strand.particles.iter().map(|&p| keep(p)).collect();
    let Some(gap) = kept.iter().position(|k| !k) else {
        return vec![strand.clone()];
    };
    // Walk the vertices once, starting after a gap when the strand is a loop so that
    // the run that wraps around the end is not cut in two.
    let start = if strand.closed { gap + 1 } else { 0 };
    let walk: Vec<usize> = (0..n).map(|i| (start + i) % n).collect();
    walk.split(|&v| !kept[v])
        .filter(|run| run.len() >= 2)
        .map(|run| piece(strand, run))
        .collect()
}

/// The pieces of `strand` once its edge `edge` is cut: an open strand in two (a piece of
/// one particle is left out; that particle is loose), a loop opened into one strand
/// that starts after the cut.
pub fn cut_pieces(strand: &Strand, edge: usize) -> Vec<Strand> {
    let n = strand.particles.len();
    let runs: Vec<Vec<usize>> = if strand.closed {
        vec![(edge + 1..edge + 1 + n).map(|v| v % n).collect()]
    } else {
        vec![(0..=edge).collect(), (edge + 1..n).collect()]
    };
    runs.iter()
        .filter(|run| run.len() >= 2)
        .map(|run| piece(strand, run))
        .collect()
}

/// The open strand through the vertices `run` of `strand` (consecutive along it), with
/// their rest lengths and the rest angles of its interior vertices.
fn piece(strand: &Strand, run: &[usize]) -> Strand {
    let n = strand.particles.len();
    let angle_at = |v: usize| -> f64 {
        if strand.rest_angles.is_empty() {
            0.0
        } else if strand.closed {
            strand.rest_angles[v]
        } else if v >= 1 && v + 1 < n {
            strand.rest_angles[v - 1]
        } else {
            0.0
        }
    };
    Strand {
        particles: run.iter().map(|&v| strand.particles[v]).collect(),
        // Edge (v, v + 1) has index v in both open and closed strands.
        rest_lengths: run.windows(2).map(|w| strand.rest_lengths[w[0]]).collect(),
        rest_angles: if strand.rest_angles.is_empty() {
            Vec::new()
        } else {
            run[1..run.len() - 1].iter().map(|&v| angle_at(v)).collect()
        },
        closed: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entities(n: u32) -> Vec<Entity> {
        (0..n)
            .map(|i| Entity::from_raw_u32(i + 1).unwrap())
            .collect()
    }

    #[test]
    fn open_strand_splits_around_a_missing_vertex() {
        let particles = entities(5);
        let strand = Strand {
            particles: particles.clone(),
            rest_lengths: vec![1.0, 2.0, 3.0, 4.0],
            rest_angles: vec![0.1, 0.2, 0.3],
            closed: false,
        };
        let gone = particles[2];
        let pieces = split_around(&strand, |p| p != gone);
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[0].particles, particles[0..2].to_vec());
        assert_eq!(pieces[0].rest_lengths, vec![1.0]);
        assert!(pieces[0].rest_angles.is_empty());
        assert_eq!(pieces[1].particles, particles[3..5].to_vec());
        assert_eq!(pieces[1].rest_lengths, vec![4.0]);
    }

    #[test]
    fn loop_opens_at_a_missing_vertex_without_cutting_the_wrap() {
        let particles = entities(5);
        let strand = Strand {
            particles: particles.clone(),
            rest_lengths: vec![1.0, 2.0, 3.0, 4.0, 5.0],
            rest_angles: vec![0.0, 0.1, 0.2, 0.3, 0.4],
            closed: true,
        };
        let gone = particles[1];
        let pieces = split_around(&strand, |p| p != gone);
        assert_eq!(pieces.len(), 1);
        let piece = &pieces[0];
        assert_eq!(
            piece.particles,
            vec![particles[2], particles[3], particles[4], particles[0]]
        );
        assert_eq!(piece.rest_lengths, vec![3.0, 4.0, 5.0]);
        assert_eq!(piece.rest_angles, vec![0.3, 0.4]);
        assert!(!piece.closed);
    }
}
