//! Collider shapes (parry's, which both avian and Rapier use) as strand outlines, and the mass a body shows at a point: pure
//! functions, no ECS.

use bevy::math::Vec2;
use parry2d::shape::TypedShape;

use crate::colliders::{ColliderShape, outline};

/// The outline of a parry shape in the collider's frame, curves within
/// `tolerance`: its vertices and whether it closes. `Err` names a shape with no
/// outline here (compounds, meshes, height fields, half-spaces, voxels).
pub fn shape_outline(shape: TypedShape<'_>, tolerance: f32) -> Result<(Vec<Vec2>, bool), String> {
    let v = |p: parry2d::math::Vector| Vec2::new(p.x, p.y);
    Ok(match shape {
        TypedShape::Ball(ball) => outline(
            &ColliderShape::Circle {
                radius: ball.radius,
            },
            tolerance,
        ),
        TypedShape::Cuboid(cuboid) => outline(
            &ColliderShape::Box {
                half_size: v(cuboid.half_extents),
            },
            tolerance,
        ),
        TypedShape::Capsule(capsule) => {
            // Our capsule lies along x about the origin: turn and move it onto the
            // segment.
            let (a, b) = (v(capsule.segment.a), v(capsule.segment.b));
            let axis = b - a;
            let half_length = 0.5 * axis.length();
            let turn = if half_length > 0.0 {
                axis / (2.0 * half_length)
            } else {
                Vec2::X
            };
            let centre = 0.5 * (a + b);
            let (points, closed) = outline(
                &ColliderShape::Capsule {
                    radius: capsule.radius,
                    half_length,
                },
                tolerance,
            );
            (
                points
                    .into_iter()
                    .map(|p| centre + turn.rotate(p))
                    .collect(),
                closed,
            )
        }
        TypedShape::Segment(segment) => (vec![v(segment.a), v(segment.b)], false),
        TypedShape::Triangle(triangle) => {
            let mut points = vec![v(triangle.a), v(triangle.b), v(triangle.c)];
            // Counter-clockwise, as every other outline.
            if (points[1] - points[0]).perp_dot(points[2] - points[0]) < 0.0 {
                points.swap(1, 2);
            }
            (points, true)
        }
        TypedShape::ConvexPolygon(polygon) => {
            (polygon.points().iter().map(|&p| v(p)).collect(), true)
        }
        TypedShape::Polyline(polyline) => {
            // A chain of segments, in order; closed when it comes back to its start.
            let indices = polyline.indices();
            let chained = indices.windows(2).all(|w| w[0][1] == w[1][0]);
            if !chained || indices.is_empty() {
                return Err("a polyline whose segments do not form one chain".into());
            }
            let vertices = polyline.vertices();
            let mut points: Vec<Vec2> =
                indices.iter().map(|s| v(vertices[s[0] as usize])).collect();
            let last = indices[indices.len() - 1][1];
            let closed = last == indices[0][0];
            if !closed {
                points.push(v(vertices[last as usize]));
            }
            (points, closed)
        }
        TypedShape::RoundCuboid(_)
        | TypedShape::RoundTriangle(_)
        | TypedShape::RoundConvexPolygon(_) => {
            return Err("a rounded shape (use a capsule or a plain polygon)".into());
        }
        _ => {
            return Err(
                "a shape with no outline (compound, mesh, height field, half-space or voxels)"
                    .into(),
            );
        }
    })
}

/// The mass a body of mass `mass` and angular inertia `inertia` shows to an impulse
/// along the unit `direction` at offset `r` from its centre of mass:
/// `1 / (1/m + (r × n)² / I)`. With no direction, the least over all directions
/// (`n ⊥ r`). An infinite inertia (rotation locked) leaves the mass.
pub fn effective_mass(mass: f64, inertia: f64, r: Vec2, direction: Option<Vec2>) -> f64 {
    let arm = match direction {
        Some(n) => r.perp_dot(n) as f64,
        None => r.length() as f64,
    };
    let turn = if inertia.is_finite() && inertia > 0.0 {
        arm * arm / inertia
    } else {
        0.0
    };
    1.0 / (1.0 / mass + turn)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry2d::shape::{Ball, Capsule, Cuboid, Polyline, Segment};

    #[test]
    fn a_capsule_along_y_is_turned_onto_its_segment() {
        let capsule = Capsule::new_y(0.5, 0.2);
        let (points, closed) = shape_outline(TypedShape::Capsule(&capsule), 1e-3).unwrap();
        assert!(closed);
        for p in points {
            // Distance to the core segment from (0, −0.5) to (0, 0.5).
            let core = Vec2::new(0.0, p.y.clamp(-0.5, 0.5)).distance(p);
            assert!(
                (0.2 * (1.0 - 1e-5)..=0.2 + 1.001e-3).contains(&core),
                "{core}"
            );
        }
    }

    #[test]
    fn boxes_balls_segments_and_chains_have_outlines() {
        let (points, closed) =
            shape_outline(TypedShape::Cuboid(&Cuboid::new(Vec2::new(1.0, 0.5))), 1e-3).unwrap();
        assert!(closed && points.len() == 4 && points.contains(&Vec2::new(1.0, 0.5)));
        let (points, _) = shape_outline(TypedShape::Ball(&Ball::new(0.3)), 1e-3).unwrap();
        assert!(
            points
                .iter()
                .all(|p| p.length() >= 0.3 && p.length() <= 0.301 + 1e-6)
        );
        let segment = Segment::new(Vec2::ZERO, Vec2::X);
        assert_eq!(
            shape_outline(TypedShape::Segment(&segment), 1e-3).unwrap(),
            (vec![Vec2::ZERO, Vec2::X], false)
        );
        let chain = Polyline::new(vec![Vec2::ZERO, Vec2::X, Vec2::ONE], None);
        assert_eq!(
            shape_outline(TypedShape::Polyline(&chain), 1e-3).unwrap(),
            (vec![Vec2::ZERO, Vec2::X, Vec2::ONE], false)
        );
    }

    #[test]
    fn effective_mass_is_the_impulse_response_of_a_rigid_body() {
        let (m, i) = (2.0, 0.5);
        let r = Vec2::new(0.0, 1.0);
        // Along the arm: the whole mass; across it: less, by the turn it causes.
        assert_eq!(effective_mass(m, i, r, Some(Vec2::Y)), 2.0);
        let across = effective_mass(m, i, r, Some(Vec2::X));
        // Δv at the point for a unit impulse: 1/m + r²/I.
        assert!((1.0 / across - (0.5 + 2.0)).abs() < 1e-12);
        assert_eq!(effective_mass(m, i, r, None), across);
        assert_eq!(effective_mass(m, f64::INFINITY, r, None), 2.0);
    }
}
