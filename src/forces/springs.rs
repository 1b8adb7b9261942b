//! Stretch springs along edges, with damping along the edge.
//!
//! Hooke's law in strain, `f = k (ℓ/L − 1) + d (v_b − v_a)·ê`, pulling the two ends
//! together when stretched. With inextensibility constraints these are unnecessary;
//! they remain for the springs-only solver and for constraint-drift studies.

use bevy::math::DVec2;

use crate::model::Edge;

/// Add the spring force of every edge with `spring` set.
pub fn add_stretch_springs(
    edges: &[Edge],
    position: &[DVec2],
    velocity: &[DVec2],
    force: &mut [DVec2],
) {
    for edge in edges.iter().filter(|e| e.spring) {
        let (a, b) = (edge.a as usize, edge.b as usize);
        let e = position[b] - position[a];
        let length = e.length();
        if length == 0.0 {
            continue; // no direction to push along
        }
        let direction = e / length;
        let strain = length / edge.rest_length - 1.0;
        let rate = (velocity[b] - velocity[a]).dot(direction);
        let f = (edge.stiffness * strain + edge.damping * rate) * direction;
        force[a] += f;
        force[b] -= f;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(stiffness: f64, damping: f64) -> Edge {
        Edge {
            spring: true,
            stiffness,
            damping,
            ..Edge::new(0, 1, 1.0)
        }
    }

    #[test]
    fn stretched_spring_pulls_ends_together() {
        let position = [DVec2::ZERO, DVec2::new(1.5, 0.0)];
        let velocity = [DVec2::ZERO; 2];
        let mut force = [DVec2::ZERO; 2];
        add_stretch_springs(&[edge(10.0, 0.0)], &position, &velocity, &mut force);
        assert_eq!(force[0], DVec2::new(5.0, 0.0));
        assert_eq!(force[1], DVec2::new(-5.0, 0.0));
    }

    #[test]
    fn damping_opposes_separation_only() {
        let position = [DVec2::ZERO, DVec2::new(1.0, 0.0)];
        let velocity = [DVec2::ZERO, DVec2::new(2.0, 3.0)];
        let mut force = [DVec2::ZERO; 2];
        add_stretch_springs(&[edge(0.0, 1.0)], &position, &velocity, &mut force);
        assert_eq!(force[1], DVec2::new(-2.0, 0.0));
        assert_eq!(force[0] + force[1], DVec2::ZERO);
    }
}
