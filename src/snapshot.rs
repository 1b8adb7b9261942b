//! Snapshots: the simulated state of a world — every particle and strand and the clock —
//! captured as plain data, and restored into another world so that the simulation
//! continues exactly as it would have (save games, reproductions of a rare event, tests).
//!
//! Particles are numbered by their position in [`StrandsSnapshot::particles`]; strands
//! refer to them by that number. Both lists are kept in the order the topology rebuild
//! sorts them in (their [`SpawnOrder`], newest first), and [`StrandsSnapshot::restore`]
//! spawns them so that the new ones sort the same way: the packed order, and with it
//! every sum of a step, is then the same as in the world captured, and a restored run
//! continues bit for bit — also after despawns, whose freed entity slots the captured
//! world reuses and the restored one does not have.

use bevy::ecs::entity::EntityHashMap;
use bevy::math::DVec2;
use bevy::prelude::*;

use crate::contact::plugin::ContactRows;
use crate::contact::rows::RowImpulse;
use crate::contact::warm::{NamedWarmStart, Partner};
use crate::schedule::synchronise;
use crate::world::clock::SimulationClock;
use crate::world::hooks::SpawnOrder;
use crate::world::particle::{
    ExternalForce, Kinematic, Mass, Particle, Pinned, Position, Sleeping, Velocity,
};
use crate::world::state::ParticleState;
use crate::world::strand::{Strand, StrandKind, StrandMaterial, StrandOf};
use crate::world::topology::Topology;

/// The snapshot format written by [`StrandsSnapshot::capture`].
pub const SNAPSHOT_VERSION: u32 = 1;

/// A particle as captured.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ParticleRecord {
    /// Position.
    pub position: DVec2,
    /// Velocity.
    pub velocity: DVec2,
    /// Mass.
    pub mass: f64,
    /// Whether it is pinned.
    #[cfg_attr(feature = "serde", serde(default))]
    pub pinned: bool,
    /// Whether it is kinematic.
    #[cfg_attr(feature = "serde", serde(default))]
    pub kinematic: bool,
    /// Its constant external force, if it has one.
    #[cfg_attr(feature = "serde", serde(default))]
    pub external_force: Option<DVec2>,
    /// The strand that owns it (index into [`StrandsSnapshot::strands`]).
    #[cfg_attr(feature = "serde", serde(default))]
    pub owner: Option<u32>,
    /// Whether it sleeps (its strand asleep; see the `sleeping` module). The rest times
    /// of the strands awake are not kept: they start again from the restore.
    #[cfg_attr(feature = "serde", serde(default))]
    pub asleep: bool,
}

/// A strand as captured: its particles by their number in the snapshot.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StrandRecord {
    /// Particles in order along the strand.
    pub particles: Vec<u32>,
    /// Rest length of each edge.
    pub rest_lengths: Vec<f64>,
    /// Rest turning angle at each bending vertex (empty: straight).
    #[cfg_attr(feature = "serde", serde(default))]
    pub rest_angles: Vec<f64>,
    /// Whether the strand is a loop.
    #[cfg_attr(feature = "serde", serde(default))]
    pub closed: bool,
    /// What it represents.
    #[cfg_attr(feature = "serde", serde(default))]
    pub kind: StrandKind,
    /// Its own material, if it has one.
    #[cfg_attr(feature = "serde", serde(default))]
    pub material: Option<StrandMaterial>,
}

/// A contact's warm start as captured: the impulse its row held at the last step,
/// which the next step starts from.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ContactRecord {
    /// The point (its number in the snapshot).
    pub point: u32,
    /// The strand it meets, if it meets that strand's nearest edge.
    #[cfg_attr(feature = "serde", serde(default))]
    pub strand: Option<u32>,
    /// The edge it meets, by its particles' numbers, if it meets a corner's second edge.
    #[cfg_attr(feature = "serde", serde(default))]
    pub edge: Option<[u32; 2]>,
    /// The impulse along the normal.
    pub normal: f64,
    /// The impulse along the tangent.
    pub tangent: f64,
}

/// The simulated state of a world.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StrandsSnapshot {
    /// The format: [`SNAPSHOT_VERSION`] for a snapshot written now; 0 (absent) for one
    /// written before kinematic particles had a marker of their own, when a pinned
    /// particle moved with its velocity — such a particle is restored kinematic.
    #[cfg_attr(feature = "serde", serde(default))]
    pub version: u32,
    /// Simulated time and steps.
    pub clock: SimulationClock,
    /// Every particle, in entity order.
    pub particles: Vec<ParticleRecord>,
    /// Every strand, in entity order.
    pub strands: Vec<StrandRecord>,
    /// The contacts' warm starts (absent in snapshots written before 2026-12-07: the
    /// continued run's first step then starts its contacts cold).
    #[cfg_attr(feature = "serde", serde(default))]
    pub contacts: Vec<ContactRecord>,
    /// The step the warm starts were taken over.
    #[cfg_attr(feature = "serde", serde(default))]
    pub contact_step: f64,
}

/// Which entity each number of a snapshot stands for.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SnapshotEntities {
    /// The entity of each particle, by its number in the snapshot.
    pub particles: Vec<Entity>,
    /// The entity of each strand, by its number in the snapshot.
    pub strands: Vec<Entity>,
}

impl SnapshotEntities {
    /// The number of `particle` in the snapshot, if it is one of its particles.
    pub fn particle_number(&self, particle: Entity) -> Option<u32> {
        // Particles are kept in entity order, so the list is sorted.
        self.particles
            .binary_search(&particle)
            .ok()
            .map(|i| i as u32)
    }

    /// The number of `strand` in the snapshot, if it is one of its strands.
    pub fn strand_number(&self, strand: Entity) -> Option<u32> {
        self.strands.binary_search(&strand).ok().map(|i| i as u32)
    }
}

/// Why a snapshot cannot be restored.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SnapshotError {
    /// A strand names a particle the snapshot does not have.
    #[error("strand {strand} names particle {particle}, but the snapshot has {count} particles")]
    MissingParticle {
        /// The strand.
        strand: usize,
        /// The particle it names.
        particle: u32,
        /// How many particles there are.
        count: usize,
    },
    /// A particle names an owner strand the snapshot does not have.
    #[error(
        "particle {particle} is owned by strand {strand}, but the snapshot has {count} strands"
    )]
    MissingOwner {
        /// The particle.
        particle: usize,
        /// The owner it names.
        strand: u32,
        /// How many strands there are.
        count: usize,
    },
    /// Something outside the particle and strand lists names a particle the snapshot
    /// does not hold.
    #[error("the snapshot names particle {0}, but does not hold it")]
    UnknownParticle(u32),
    /// The world already holds particles or strands, so the restored entities could
    /// not keep the captured order.
    #[error("the world already holds {0} particles or strands; restore into an empty one")]
    NotEmpty(usize),
    /// A contact's warm start names a particle or strand the snapshot does not have,
    /// or not exactly one partner, or its impulse or step is not a finite number (the
    /// step not positive).
    #[error(
        "contact {contact} names a particle or strand the snapshot does not have, or not exactly one of a strand and an edge, or its impulse or the contacts' step is not finite"
    )]
    BadContact {
        /// The contact (its index).
        contact: usize,
    },
}

impl StrandsSnapshot {
    /// Capture every particle and strand of `world`, and the clock.
    pub fn capture(world: &mut World) -> (StrandsSnapshot, SnapshotEntities) {
        let mut strand_query = world.query_filtered::<Entity, With<Strand>>();
        let mut strands: Vec<Entity> = strand_query.iter(world).collect();
        let mut particle_query = world.query_filtered::<Entity, With<Particle>>();
        let mut particles: Vec<Entity> = particle_query.iter(world).collect();
        if let Some(order) = world.get_resource::<SpawnOrder>() {
            strands.sort_by_cached_key(|&e| order.strand_key(e));
            particles.sort_by_cached_key(|&e| order.particle_key(e));
        } else {
            strands.sort();
            particles.sort();
        }
        let entities = SnapshotEntities { particles, strands };
        let number: EntityHashMap<u32> = entities
            .particles
            .iter()
            .enumerate()
            .map(|(i, &e)| (e, i as u32))
            .collect();
        let particles = entities
            .particles
            .iter()
            .map(|&e| {
                let entity = world.entity(e);
                ParticleRecord {
                    position: entity.get::<Position>().map_or(DVec2::ZERO, |p| p.0),
                    velocity: entity.get::<Velocity>().map_or(DVec2::ZERO, |v| v.0),
                    mass: entity.get::<Mass>().map_or(1.0, |m| m.0),
                    pinned: entity.contains::<Pinned>(),
                    kinematic: entity.contains::<Kinematic>(),
                    external_force: entity.get::<ExternalForce>().map(|f| f.0),
                    asleep: entity.contains::<Sleeping>(),
                    owner: entity
                        .get::<StrandOf>()
                        .and_then(|owner| entities.strand_number(owner.0)),
                }
            })
            .collect();
        let strands = entities
            .strands
            .iter()
            .map(|&e| {
                let entity = world.entity(e);
                let strand = entity.get::<Strand>().expect("queried with Strand");
                StrandRecord {
                    // A strand naming a despawned particle is split at the next rebuild;
                    // capture what is there now and leave the gap to that rebuild.
                    particles: strand
                        .particles
                        .iter()
                        .map(|p| number.get(p).copied().unwrap_or(u32::MAX))
                        .collect(),
                    rest_lengths: strand.rest_lengths.clone(),
                    rest_angles: strand.rest_angles.clone(),
                    closed: strand.closed,
                    kind: entity.get::<StrandKind>().copied().unwrap_or_default(),
                    material: entity.get::<StrandMaterial>().copied(),
                }
            })
            .collect();
        let (contacts, contact_step) = capture_contacts(world, &entities);
        let snapshot = StrandsSnapshot {
            version: SNAPSHOT_VERSION,
            clock: *world.resource::<SimulationClock>(),
            particles,
            strands,
            contacts,
            contact_step,
        };
        (snapshot, entities)
    }

    /// Check that every number the snapshot uses refers to something it holds.
    pub fn check(&self) -> Result<(), SnapshotError> {
        for (strand, record) in self.strands.iter().enumerate() {
            if let Some(&particle) = record
                .particles
                .iter()
                .find(|&&p| p as usize >= self.particles.len())
            {
                return Err(SnapshotError::MissingParticle {
                    strand,
                    particle,
                    count: self.particles.len(),
                });
            }
        }
        for (contact, record) in self.contacts.iter().enumerate() {
            let particles = [record.point]
                .into_iter()
                .chain(record.edge.into_iter().flatten());
            let strand_ok = record
                .strand
                .is_none_or(|s| (s as usize) < self.strands.len());
            let one_partner = record.strand.is_some() != record.edge.is_some();
            let finite = record.normal.is_finite()
                && record.tangent.is_finite()
                && self.contact_step.is_finite()
                && self.contact_step > 0.0;
            if !strand_ok
                || !one_partner
                || !finite
                || particles
                    .into_iter()
                    .any(|p| p as usize >= self.particles.len())
            {
                return Err(SnapshotError::BadContact { contact });
            }
        }
        for (particle, record) in self.particles.iter().enumerate() {
            if let Some(strand) = record.owner.filter(|&s| s as usize >= self.strands.len()) {
                return Err(SnapshotError::MissingOwner {
                    particle,
                    strand,
                    count: self.strands.len(),
                });
            }
        }
        Ok(())
    }

    /// Spawn the snapshot's particles and strands into `world`, which must hold none
    /// yet, and set its clock. Nothing is spawned if the snapshot is inconsistent.
    pub fn restore(&self, world: &mut World) -> Result<SnapshotEntities, SnapshotError> {
        self.check()?;
        let mut existing = world.query_filtered::<(), Or<(With<Particle>, With<Strand>)>>();
        let count = existing.iter(world).count();
        if count > 0 {
            return Err(SnapshotError::NotEmpty(count));
        }
        // Spawned in reverse, the last captured first, they are numbered in reverse, and
        // sort newest first in the captured order (as fresh entities also do by their
        // own `Ord`, for a world without `SpawnOrder`).
        let mut strands = vec![Entity::PLACEHOLDER; self.strands.len()];
        for (slot, record) in strands.iter_mut().zip(&self.strands).rev() {
            let mut entity = world.spawn(record.kind);
            if let Some(material) = record.material {
                entity.insert(material);
            }
            *slot = entity.id();
        }
        let mut particles = vec![Entity::PLACEHOLDER; self.particles.len()];
        for (slot, record) in particles.iter_mut().zip(&self.particles).rev() {
            let mut entity = world.spawn((
                Particle,
                Position(record.position),
                Velocity(record.velocity),
                Mass(record.mass),
            ));
            // Before version 1 a pinned particle with a velocity was driven by it.
            let moving_pin = self.version == 0 && record.velocity != DVec2::ZERO;
            if record.kinematic || record.pinned && moving_pin {
                entity.insert(Kinematic);
            } else if record.pinned {
                entity.insert(Pinned);
            }
            if let Some(force) = record.external_force {
                entity.insert(ExternalForce(force));
            }
            if record.asleep {
                entity.insert(Sleeping);
            }
            if let Some(owner) = record.owner {
                entity.insert(StrandOf(strands[owner as usize]));
            }
            *slot = entity.id();
        }
        // Strands are numbered in the order their `Strand` arrives, newest first in
        // the topology: insert the last captured first.
        for (&entity, record) in strands.iter().zip(&self.strands).rev() {
            world.entity_mut(entity).insert(Strand {
                particles: record
                    .particles
                    .iter()
                    .map(|&p| particles[p as usize])
                    .collect(),
                rest_lengths: record.rest_lengths.clone(),
                rest_angles: record.rest_angles.clone(),
                closed: record.closed,
            });
        }
        *world.resource_mut::<SimulationClock>() = self.clock;
        // Scene logic at the start of the next tick reads the topology and the packed
        // state as the last tick left them: build them now, as that tick would have.
        synchronise(world);
        let restored = SnapshotEntities { particles, strands };
        self.restore_contacts(world, &restored);
        let in_order = match world.get_resource::<SpawnOrder>() {
            Some(order) => {
                restored
                    .particles
                    .is_sorted_by_key(|&e| order.particle_key(e))
                    && restored.strands.is_sorted_by_key(|&e| order.strand_key(e))
            }
            None => restored.particles.is_sorted() && restored.strands.is_sorted(),
        };
        if !in_order {
            warn!(
                "bevy_strands: the restored entities do not sort as the captured ones did; \
                 the run continues, but not bit for bit"
            );
        }
        Ok(restored)
    }
}

impl StrandsSnapshot {
    /// Give the restored world's contact rows the captured warm starts.
    fn restore_contacts(&self, world: &mut World, restored: &SnapshotEntities) {
        if self.contacts.is_empty() || !world.contains_resource::<ContactRows>() {
            return;
        }
        let particle = |p: u32| restored.particles.get(p as usize).copied();
        let named: Vec<NamedWarmStart> = (self.contacts.iter())
            .filter_map(|c| {
                let partner = match (c.strand, c.edge) {
                    (Some(s), None) => Partner::Strand(*restored.strands.get(s as usize)?),
                    (None, Some([a, b])) => Partner::Edge(particle(a)?, particle(b)?),
                    _ => return None, // refused by `check`
                };
                Some(NamedWarmStart {
                    point: particle(c.point)?,
                    partner,
                    impulse: RowImpulse {
                        normal: c.normal,
                        tangent: c.tangent,
                    },
                })
            })
            .collect();
        world.resource_scope(|world, mut rows: Mut<ContactRows>| {
            let entities = &world.resource::<ParticleState>().entity;
            rows.restore_warm_starts(
                &named,
                self.contact_step,
                entities,
                world.resource::<Topology>(),
            );
        });
    }
}

/// The contact rows' warm starts of `world`, numbered as `entities` numbers the
/// snapshot, and the step they were taken over.
fn capture_contacts(world: &World, entities: &SnapshotEntities) -> (Vec<ContactRecord>, f64) {
    let Some(rows) = world.get_resource::<ContactRows>() else {
        return (Vec::new(), 0.0);
    };
    let (named, step) = rows.named_warm_starts();
    let numbers = |list: &[Entity]| -> EntityHashMap<u32> {
        (list.iter().enumerate())
            .map(|(i, &e)| (e, i as u32))
            .collect()
    };
    let (particles, strands) = (numbers(&entities.particles), numbers(&entities.strands));
    let particle = |e: Entity| particles.get(&e).copied();
    let records = (named.iter())
        .filter_map(|w| {
            let (strand, edge) = match w.partner {
                Partner::Strand(s) => (Some(*strands.get(&s)?), None),
                Partner::Edge(a, b) => (None, Some([particle(a)?, particle(b)?])),
            };
            Some(ContactRecord {
                point: particle(w.point)?,
                strand,
                edge,
                normal: w.impulse.normal,
                tangent: w.impulse.tangent,
            })
        })
        .collect();
    (records, step)
}
