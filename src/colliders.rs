//! Colliders that are not strands: circles, boxes, capsules and polylines on any entity
//! with a `GlobalTransform`. Each is built as a wall strand of its own — its outline's
//! vertices anchored to the entity ([`Anchor`]), its edges static obstacles — so strands
//! meet it through the same continuous point–edge detection, impulses and fail-safe as
//! they meet each other: the same no-tunnelling guarantee, and a collider that moves
//! pushes strands as a body of infinite mass. Curved outlines are polygons that
//! circumscribe the curve, with at most `tolerance` between them, so nothing ever
//! reaches inside the true shape.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::anchors::Anchor;
use crate::model::validate::rest_lengths_of;
use crate::schedule::{StrandsTick, TickSet};
use crate::world::particle::{Particle, Position, Velocity};
use crate::world::strand::{Strand, StrandKind, StrandMaterial, StrandOf};

/// A collider's shape, in its entity's local frame.
#[derive(Clone, Debug, PartialEq, Reflect)]
pub enum ColliderShape {
    /// A disc of this radius about the origin.
    Circle {
        /// Radius.
        radius: f32,
    },
    /// An axis-aligned box of these half extents about the origin.
    Box {
        /// Half width and half height.
        half_size: Vec2,
    },
    /// A segment along x of half length `half_length`, rounded by `radius`.
    Capsule {
        /// Radius of the rounding.
        radius: f32,
        /// Half the length of the straight part.
        half_length: f32,
    },
    /// A chain of segments; closed, the last point joins the first.
    Polyline {
        /// The vertices.
        points: Vec<Vec2>,
        /// Whether it is a loop.
        closed: bool,
    },
}

/// Make strands collide with this entity's shape.
///
/// ```
/// use bevy::math::DVec2;
/// use bevy::prelude::*;
/// use bevy_strands::prelude::*;
///
/// let mut app = App::new();
/// app.add_plugins((MinimalPlugins, StrandsPlugin::manual()));
/// app.finish();
/// app.cleanup();
/// // A post of radius 10 cm; a rope dropped across it drapes over it.
/// app.world_mut().spawn((
///     StrandCollider::new(ColliderShape::Circle { radius: 0.1 }),
///     Transform::default(),
///     GlobalTransform::default(),
/// ));
/// let rope = StrandBuilder::line(DVec2::new(-0.3, 0.2), DVec2::X, 13, 0.05)
///     .spawn_in(app.world_mut())
///     .unwrap();
/// for _ in 0..60 {
///     app.world_mut().run_schedule(StrandsTick);
/// }
/// let strand = app.world().get::<Strand>(rope).unwrap();
/// for &p in &strand.particles {
///     let x = app.world().get::<Position>(p).unwrap().0;
///     assert!(x.length() >= 0.1, "inside the post at {x}");
/// }
/// // Its middle lies on top of the post.
/// let middle = app.world().get::<Position>(strand.particles[6]).unwrap().0;
/// assert!(middle.y > 0.09 && middle.y < 0.12, "{middle}");
/// ```
#[derive(Component, Clone, Debug, PartialEq, Reflect)]
#[reflect(Component)]
pub struct StrandCollider {
    /// The shape.
    pub shape: ColliderShape,
    /// How far the polygon of a curved outline may stand off the curve.
    pub tolerance: f32,
}

impl StrandCollider {
    /// A collider of `shape` with curves within a millimetre.
    pub fn new(shape: ColliderShape) -> Self {
        Self {
            shape,
            tolerance: 1e-3,
        }
    }
}

/// On a collider's wall strand: the collider entity it outlines.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, Reflect)]
#[reflect(Component)]
pub struct ColliderOf(pub Entity);

/// On a collider entity: its wall strand.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, Reflect)]
#[reflect(Component)]
pub struct ColliderStrand(pub Entity);

/// Where new outlines are built in the tick: a coupling that builds its own outlines
/// (the avian one) runs before it, so that each collider gets one.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct OutlineBuild;

/// Builds and removes the collider outlines.
pub struct ColliderPlugin;

impl Plugin for ColliderPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<StrandCollider>()
            .register_type::<ColliderOf>()
            .register_type::<ColliderStrand>()
            .add_systems(
                StrandsTick,
                (remove_orphan_outlines, build_outlines.in_set(OutlineBuild))
                    .chain()
                    .before(TickSet::Topology),
            );
    }
}

/// The outline of `shape`: its vertices in order, and whether it closes.
pub fn outline(shape: &ColliderShape, tolerance: f32) -> (Vec<Vec2>, bool) {
    // A circumscribed polygon's corners stand r (1 / cos(θ/2) − 1) off a circle of
    // radius r, θ the angle a side spans: within `tolerance` for θ ≤ 2 acos(r/(r + tol)).
    let sides = |r: f32, turn: f32| {
        let per_side = 2.0 * (r / (r + tolerance.max(1e-6 * r))).acos();
        (turn / per_side).ceil().max(1.0) as usize
    };
    let arc = |centre: Vec2, r: f32, from: f32, turn: f32, out: &mut Vec<Vec2>| {
        let n = sides(r, turn);
        let step = turn / n as f32;
        let corner = r / (0.5 * step).cos();
        // Corners halfway between the tangent points, plus the ends on the arc's radius.
        out.push(centre + r * Vec2::from_angle(from));
        for k in 0..n {
            out.push(centre + corner * Vec2::from_angle(from + (k as f32 + 0.5) * step));
        }
        out.push(centre + r * Vec2::from_angle(from + turn));
    };
    match shape {
        ColliderShape::Circle { radius } => {
            let n = sides(*radius, std::f32::consts::TAU).max(3);
            let step = std::f32::consts::TAU / n as f32;
            let corner = radius / (0.5 * step).cos();
            (
                (0..n)
                    .map(|k| corner * Vec2::from_angle(k as f32 * step))
                    .collect(),
                true,
            )
        }
        ColliderShape::Box { half_size: h } => (
            vec![
                Vec2::new(-h.x, -h.y),
                Vec2::new(h.x, -h.y),
                *h,
                Vec2::new(-h.x, h.y),
            ],
            true,
        ),
        ColliderShape::Capsule {
            radius,
            half_length,
        } => {
            let half = std::f32::consts::PI;
            let mut points = Vec::new();
            arc(
                Vec2::new(*half_length, 0.0),
                *radius,
                -0.5 * half,
                half,
                &mut points,
            );
            arc(
                Vec2::new(-half_length, 0.0),
                *radius,
                0.5 * half,
                half,
                &mut points,
            );
            points.dedup_by(|a, b| a.distance(*b) < 1e-6 * radius);
            (points, true)
        }
        ColliderShape::Polyline { points, closed } => (points.clone(), *closed),
    }
}

/// A new collider's outline: a wall strand whose vertices are anchored to it.
fn build_outlines(
    mut commands: Commands,
    colliders: Query<(Entity, &StrandCollider, &GlobalTransform), Without<ColliderStrand>>,
) {
    for (entity, collider, transform) in &colliders {
        let (points, closed) = outline(&collider.shape, collider.tolerance);
        spawn_anchored_outline(&mut commands, entity, &points, closed, transform);
    }
}

/// The outline of `points` (the collider's frame) placed by the collider's transform,
/// its vertices [`Anchor`]ed to the collider entity.
pub(crate) fn spawn_anchored_outline(
    commands: &mut Commands,
    collider: Entity,
    points: &[Vec2],
    closed: bool,
    transform: &GlobalTransform,
) {
    let world_point = |p: Vec2| {
        transform
            .transform_point(p.extend(0.0))
            .truncate()
            .as_dvec2()
    };
    spawn_outline(commands, collider, points, closed, world_point, |p| {
        Anchor {
            target: collider,
            offset: p,
        }
    });
}

/// Spawn the wall strand outlining `collider`: one particle per vertex of `points`
/// (in the collider's frame) at `world_point(p)`, each given `attach(p)` to follow the
/// collider. Refused, with a warning, for too few or coincident points. Returns the
/// strand and its particles.
pub(crate) fn spawn_outline<B: Bundle>(
    commands: &mut Commands,
    collider: Entity,
    points: &[Vec2],
    closed: bool,
    world_point: impl Fn(Vec2) -> DVec2,
    attach: impl Fn(Vec2) -> B,
) -> Option<(Entity, Vec<Entity>)> {
    if points.len() < if closed { 3 } else { 2 } {
        warn!("bevy_strands: collider {collider} has too few points for an outline");
        return None;
    }
    let at: Vec<DVec2> = points.iter().map(|&p| world_point(p)).collect();
    let rest_lengths = match rest_lengths_of(&at, closed) {
        Ok(lengths) => lengths,
        Err(problem) => {
            warn!("bevy_strands: collider {collider} has no outline: {problem}");
            return None;
        }
    };
    let strand = commands.spawn_empty().id();
    let particles: Vec<Entity> = points
        .iter()
        .zip(&at)
        .map(|(&p, &x)| {
            commands
                .spawn((
                    Particle,
                    Position(x),
                    Velocity(DVec2::ZERO),
                    attach(p),
                    StrandOf(strand),
                ))
                .id()
        })
        .collect();
    commands.entity(strand).insert((
        Strand {
            particles: particles.clone(),
            rest_lengths,
            rest_angles: Vec::new(),
            closed,
        },
        StrandKind::Wall,
        StrandMaterial::INERT,
        ColliderOf(collider),
    ));
    commands.entity(collider).insert(ColliderStrand(strand));
    Some((strand, particles))
}

/// An outline whose collider is gone (or no longer a collider) goes too.
fn remove_orphan_outlines(
    mut commands: Commands,
    outlines: Query<(Entity, &ColliderOf)>,
    colliders: Query<(), With<StrandCollider>>,
) {
    for (strand, of) in &outlines {
        if !colliders.contains(of.0) {
            commands.entity(strand).despawn();
            if let Ok(mut collider) = commands.get_entity(of.0) {
                collider.remove::<ColliderStrand>();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_circles_outline_contains_it_within_the_tolerance() {
        for (radius, tolerance) in [(0.1f32, 1e-3f32), (1.0, 1e-3), (0.05, 1e-4)] {
            let (points, closed) = outline(&ColliderShape::Circle { radius }, tolerance);
            assert!(closed && points.len() >= 3);
            for (k, &p) in points.iter().enumerate() {
                let q = points[(k + 1) % points.len()];
                // The edge's nearest point to the centre is no closer than the radius
                // (less rounding), and its corners no farther than the tolerance.
                let t = (-p.dot(q - p) / (q - p).length_squared()).clamp(0.0, 1.0);
                let nearest = (p + t * (q - p)).length();
                assert!(nearest >= radius * (1.0 - 1e-5), "{nearest} < {radius}");
                assert!(
                    p.length() - radius <= tolerance * 1.001,
                    "{}",
                    p.length() - radius
                );
            }
        }
    }

    #[test]
    fn a_capsules_outline_contains_it_within_the_tolerance() {
        let (radius, half_length, tolerance) = (0.05f32, 0.2f32, 1e-3f32);
        let (points, _) = outline(
            &ColliderShape::Capsule {
                radius,
                half_length,
            },
            tolerance,
        );
        // Distance from a point to the capsule's core segment.
        let core = |p: Vec2| Vec2::new(p.x.clamp(-half_length, half_length), 0.0).distance(p);
        for (k, &p) in points.iter().enumerate() {
            let q = points[(k + 1) % points.len()];
            assert!(core(p) >= radius * (1.0 - 1e-5) && core(p) <= radius + tolerance * 1.001);
            for s in 0..=20 {
                let x = p.lerp(q, s as f32 / 20.0);
                assert!(core(x) >= radius * (1.0 - 1e-4), "{x} is inside");
            }
        }
    }
}
