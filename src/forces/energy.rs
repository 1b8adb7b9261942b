//! The energies the forces store: what a scene's mechanical energy is made of, for the
//! report's account of energy gained where nothing drives the motion. Pure kernels.

use bevy::math::DVec2;

use crate::model::geometry::{turning_angle, wrap_angle};
use crate::model::{Bend, Edge};

/// Gravitational potential energy `−Σ m g·x` of the particles `counted` marks.
pub fn gravity_energy(mass: &[f64], position: &[DVec2], counted: &[bool], gravity: DVec2) -> f64 {
    (mass.iter().zip(position).zip(counted))
        .filter(|(_, c)| **c)
        .map(|((m, x), _)| -m * gravity.dot(*x))
        .sum()
}

/// Kinetic energy `Σ ½ m v²` of the particles `counted` marks.
pub fn kinetic_energy(mass: &[f64], velocity: &[DVec2], counted: &[bool]) -> f64 {
    (mass.iter().zip(velocity).zip(counted))
        .filter(|(_, c)| **c)
        .map(|((m, v), _)| 0.5 * m * v.length_squared())
        .sum()
}

/// The angle model's bending energy `Σ K (θ − θ̄)²`.
pub fn angle_bending_energy(bends: &[Bend], position: &[DVec2]) -> f64 {
    bends
        .iter()
        .map(|b| {
            let (a, s, c) = (b.a as usize, b.s as usize, b.b as usize);
            let theta = turning_angle(position[s] - position[a], position[c] - position[s]);
            b.stiffness * wrap_angle(theta - b.rest_angle).powi(2)
        })
        .sum()
}

/// The stretch springs' energy `Σ ½ (k / L) (ℓ − L)²` (the force is `k` times the strain).
pub fn spring_energy(edges: &[Edge], position: &[DVec2]) -> f64 {
    edges
        .iter()
        .filter(|e| e.spring && e.rest_length > 0.0)
        .map(|e| {
            let stretch = position[e.b as usize].distance(position[e.a as usize]) - e.rest_length;
            0.5 * e.stiffness / e.rest_length * stretch * stretch
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_energy_is_minus_the_work_of_its_force() {
        // A small displacement changes each energy by minus the force's work.
        let position = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(0.11, 0.02),
            DVec2::new(0.2, 0.09),
        ];
        let bends = [Bend {
            a: 0,
            s: 1,
            b: 2,
            rest_angle: 0.2,
            stiffness: 0.7,
            damping: 0.0,
            rest_lengths: [0.1, 0.1],
        }];
        let edges = [Edge {
            spring: true,
            stiffness: 30.0,
            damping: 0.0,
            rest_length: 0.1,
            ..Edge::new(0, 1, 0.1)
        }];
        let mut force = vec![DVec2::ZERO; 3];
        crate::forces::bending::add_bending(&bends, &position, &[DVec2::ZERO; 3], &mut force);
        crate::forces::springs::add_stretch_springs(
            &edges,
            &position,
            &[DVec2::ZERO; 3],
            &mut force,
        );
        let energy = |x: &[DVec2]| angle_bending_energy(&bends, x) + spring_energy(&edges, x);
        let step = 1e-7;
        for i in 0..3 {
            for d in [DVec2::X, DVec2::Y] {
                let mut moved = position.clone();
                moved[i] += step * d;
                let change = energy(&moved) - energy(&position);
                assert!(
                    (change + step * force[i].dot(d)).abs() < 1e-11,
                    "particle {i}, {d}: {change} against {}",
                    -step * force[i].dot(d)
                );
            }
        }
        let counted = [true, false, true];
        let mass = [1.0, 2.0, 3.0];
        let g = DVec2::new(0.0, -9.81);
        assert!((gravity_energy(&mass, &position, &counted, g) - 9.81 * 3.0 * 0.09).abs() < 1e-12);
        let velocity = [DVec2::X, DVec2::Y, DVec2::new(0.0, 2.0)];
        assert_eq!(kinetic_energy(&mass, &velocity, &counted), 0.5 + 6.0);
    }
}
