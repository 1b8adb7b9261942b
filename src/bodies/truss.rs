//! A dynamic body inside the strands' solve: a rigid frame of particles and edges.
//!
//! The closed outline of a dynamic body's collider gets a particle at the body's centre
//! of mass and spokes from it to every vertex but one: a fan of triangles, rigid with
//! no edge to spare (2n − 1 edges for n + 1 particles), so the exact projection keeps
//! it rigid through every contact. Its masses are the body's: each vertex `I / Σ r²`
//! (the frame's inertia is the body's), the centre the rest of the mass (the frame's
//! mass is the body's). A strand that lands on the body therefore meets the body's own
//! mass and inertia inside the step, both ways at once; only what happens to the body
//! in its engine (its other contacts, joints, the user's forces) reaches the strands a
//! tick late. A particle anchored to such a body is tied into the frame by two edges to the
//! nearest outline edge's ends ([`Rigged`]), so a rope hangs on the frame itself.

use bevy::math::DVec2;
use bevy::prelude::*;

use super::anchor::BodyAnchor;
use super::view::{BodyHeld, BodyView};
use crate::colliders::ColliderOf;
use crate::model::validate::rest_lengths_of;
use crate::world::config::{CollisionConfig, StrandsConfig};
use crate::world::particle::{Particle, Position, Velocity};
use crate::world::strand::{Strand, StrandKind, StrandMaterial, StrandOf};

/// On a particle that stands for part of a body: a vertex of its outline or the
/// centre of its frame. It carries a share of the body's mass in place of its own.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct OutlineVertex {
    /// The frame's centre (else an outline vertex).
    pub centre: bool,
    /// How many outline vertices the body has.
    pub vertices: u32,
    /// `1 / Σ r²` over the vertices, `r` from the body's centre of mass.
    pub inverse_spread: f64,
    /// Whether the outline is a closed frame with a centre.
    pub framed: bool,
}

impl OutlineVertex {
    /// This particle's share of a body of `mass` and angular inertia `inertia`.
    ///
    /// In a frame, vertices of `I / Σ r²` give the frame the body's inertia, the centre
    /// keeps the rest of the mass (at least a tenth). An open outline has no centre: its
    /// vertices are held to `Σ m ≤ M` and `Σ m r² ≤ I`, so that what they take in a
    /// step never asks more of the body than it has.
    pub fn mass(&self, mass: f64, inertia: f64) -> f64 {
        let n = self.vertices.max(1) as f64;
        let cap = if self.framed { 0.9 } else { 1.0 } * mass / n;
        let by_inertia = if inertia.is_finite() {
            inertia * self.inverse_spread
        } else {
            f64::INFINITY
        };
        let vertex = by_inertia.min(cap);
        if self.centre {
            mass - n * vertex
        } else {
            vertex
        }
    }
}

/// On a dynamic body with a frame: its collider, the outline's vertices and their
/// points in the body's frame.
#[derive(Component, Clone, Debug)]
pub struct BodyTruss {
    /// The collider whose outline it is.
    pub collider: Entity,
    /// The vertex particles, in order around the outline.
    pub vertices: Vec<Entity>,
    /// Their points in the body's frame.
    pub offsets: Vec<Vec2>,
    /// The centre particle, and its point in the body's frame.
    pub hub: (Entity, Vec2),
}

/// On an anchored particle tied into its body's frame: the two edges that tie it, and
/// where on the body (in its frame) it was tied, which it is held to from then on.
#[derive(Component, Clone, Copy, Debug)]
pub struct Rigged {
    /// The ties.
    pub links: [Entity; 2],
    /// The particle's point on the body.
    pub offset: Vec2,
}

/// Spawn the frame of a body's closed outline: the centre particle and the spokes.
/// `vertices` and `offsets` are the outline's particles and their body-frame points,
/// `centre` the body's centre of mass in its frame, `role` the vertices' share,
/// `to_world` the body's pose.
pub(super) fn spawn_truss(
    commands: &mut Commands,
    (collider, body): (Entity, Entity),
    (vertices, offsets): (&[Entity], &[Vec2]),
    centre: Vec2,
    role: OutlineVertex,
    to_world: impl Fn(Vec2) -> DVec2,
) {
    let n = vertices.len();
    let hub = commands.spawn_empty().id();
    for (k, (&v, &offset)) in vertices.iter().zip(offsets).enumerate().take(n - 1) {
        let Ok(rest_lengths) = rest_lengths_of(&[centre.as_dvec2(), offset.as_dvec2()], false)
        else {
            continue;
        };
        let spoke = commands
            .spawn((
                Strand {
                    particles: vec![hub, v],
                    rest_lengths,
                    rest_angles: Vec::new(),
                    closed: false,
                },
                StrandKind::Wall,
                StrandMaterial::INERT,
                ColliderOf(collider),
            ))
            .id();
        if k == 0 {
            // The hub goes when its first spoke does.
            commands.entity(hub).insert(StrandOf(spoke));
        }
    }
    commands.entity(hub).insert((
        Particle,
        Position(to_world(centre)),
        Velocity(DVec2::ZERO),
        BodyAnchor {
            body,
            offset: centre,
        },
        OutlineVertex {
            centre: true,
            ..role
        },
    ));
    commands.entity(body).insert(BodyTruss {
        collider,
        vertices: vertices.to_vec(),
        offsets: offsets.to_vec(),
        hub: (hub, centre),
    });
}

/// Tie each anchored particle of a framed body into the frame: an edge to the frame's
/// centre and one to the spoked vertex that makes the stoutest triangle with it (the
/// ties of a hook on a crate's lid carry the load straight down the first). The ties
/// are inside the body, where no strand goes; bodies' edges never meet each other. A
/// tie whose edges are gone (the outline was removed) is dropped, and the particle is
/// coupled alone.
pub(super) fn rig_anchors(
    mut commands: Commands,
    anchors: Query<(Entity, &BodyAnchor, &Position, Option<&Rigged>), Without<OutlineVertex>>,
    positions: Query<&Position>,
    trusses: Query<(&BodyTruss, &BodyView, &BodyHeld)>,
    config: Res<StrandsConfig>,
    collisions: Res<CollisionConfig>,
    strands: Query<(), With<Strand>>,
) {
    for (particle, anchor, position, rigged) in &anchors {
        if let Some(Rigged { links, .. }) = rigged {
            if links.iter().all(|&l| strands.contains(l)) {
                continue;
            }
            commands.entity(particle).remove::<Rigged>();
        }
        let Ok((truss, body, held)) = trusses.get(anchor.body) else {
            continue;
        };
        // Where the frame is: where the strands will take the body up.
        let (body, _) = body.at_tick_start(held, config.tick_seconds(), collisions.thickness);
        // Tied where it is (a tick's motion off its anchor point at most), so that the
        // ties start at their length; it is held there on the body from now on.
        let at = position.0;
        let offset = body.local_point(at.as_vec2());
        let (hub, centre) = truss.hub;
        let Some(k) = stoutest_vertex(&truss.offsets, centre, offset) else {
            continue;
        };
        let world = |p: Vec2| body.world_point(p).as_dvec2();
        let mut links = [Entity::PLACEHOLDER; 2];
        for (link, (other, at_other)) in links
            .iter_mut()
            .zip([(hub, centre), (truss.vertices[k], truss.offsets[k])])
        {
            let there = positions
                .get(other)
                .map_or_else(|_| world(at_other), |p| p.0);
            let Ok(rest_lengths) = rest_lengths_of(&[at, there], false) else {
                return;
            };
            *link = commands
                .spawn((
                    Strand {
                        particles: vec![particle, other],
                        rest_lengths,
                        rest_angles: Vec::new(),
                        closed: false,
                    },
                    StrandKind::Wall,
                    StrandMaterial::INERT,
                    ColliderOf(truss.collider),
                ))
                .id();
        }
        commands.entity(particle).insert(Rigged { links, offset });
    }
}

/// The vertex (one with a spoke: all but the last) that, with the centre, makes the
/// triangle with `point` whose smallest angle is largest: the best conditioned tie.
fn stoutest_vertex(offsets: &[Vec2], centre: Vec2, point: Vec2) -> Option<usize> {
    let smallest_angle = |v: Vec2| {
        let corners = [(point, centre, v), (centre, v, point), (v, point, centre)];
        corners
            .iter()
            .map(|&(p, a, b)| (a - p).angle_to(b - p).abs())
            .fold(f32::INFINITY, f32::min)
    };
    let spoked = offsets.len().checked_sub(1)?;
    (0..spoked)
        .map(|k| (smallest_angle(offsets[k]), k))
        .filter(|(angle, _)| angle.is_finite())
        .max_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, k)| k)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_has_the_bodys_mass_and_inertia() {
        // A 0.2 m square of 4 kg: I = M (w² + h²) / 12.
        let (mass, inertia) = (4.0, 4.0 * 0.08 / 12.0);
        let corners = [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)];
        let spread: f64 = corners.iter().map(|(x, y)| x * x + y * y).sum();
        let vertex = OutlineVertex {
            centre: false,
            vertices: 4,
            inverse_spread: 1.0 / spread,
            framed: true,
        };
        let centre = OutlineVertex {
            centre: true,
            ..vertex
        };
        let (mv, mc) = (vertex.mass(mass, inertia), centre.mass(mass, inertia));
        assert!((4.0 * mv + mc - mass).abs() < 1e-12);
        assert!((mv * spread - inertia).abs() < 1e-12);
        // An open outline never outweighs the body.
        let open = OutlineVertex {
            framed: false,
            ..vertex
        };
        assert!(4.0 * open.mass(mass, f64::INFINITY) <= mass + 1e-12);
    }

    #[test]
    fn a_hook_on_a_lid_is_tied_to_the_centre_and_a_top_corner() {
        let square = [
            Vec2::new(-1.0, -1.0),
            Vec2::new(1.0, -1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(-1.0, 1.0),
        ];
        // Corner 3 has no spoke: of the others, the top one.
        let k = stoutest_vertex(&square, Vec2::ZERO, Vec2::new(0.0, 1.1)).unwrap();
        assert_eq!(k, 2);
    }
}
