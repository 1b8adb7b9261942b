//! The bending force between consecutive edges.
//!
//! Per bending vertex s between edges e₁ = x_s − x_a and e₂ = x_b − x_s, with signed
//! turning angle θ = atan2(e₁ × e₂, e₁ · e₂), the energy is `K (θ − θ̄)²` with
//! K = k_b / ℓ̄. Its gradient: ∂θ/∂x_a = e₁⊥/|e₁|², ∂θ/∂x_b = e₂⊥/|e₂|², and ∂θ/∂x_s
//! their negated sum. Damping acts on the angle rate θ̇ = Σ ∂θ/∂x_i · v_i.

use bevy::math::DVec2;

use crate::model::Bend;
use crate::model::geometry::{turning_angle, wrap_angle};

/// Add the bending force of every element.
pub fn add_bending(bends: &[Bend], position: &[DVec2], velocity: &[DVec2], force: &mut [DVec2]) {
    for bend in bends {
        let (a, s, b) = (bend.a as usize, bend.s as usize, bend.b as usize);
        let e1 = position[s] - position[a];
        let e2 = position[b] - position[s];
        let (l1, l2) = (e1.length_squared(), e2.length_squared());
        if l1 == 0.0 || l2 == 0.0 {
            continue;
        }
        let theta = turning_angle(e1, e2);
        let grad_a = e1.perp() / l1;
        let grad_b = e2.perp() / l2;
        let grad_s = -(grad_a + grad_b);
        let rate = grad_a.dot(velocity[a]) + grad_s.dot(velocity[s]) + grad_b.dot(velocity[b]);
        let magnitude =
            -2.0 * bend.stiffness * wrap_angle(theta - bend.rest_angle) - bend.damping * rate;
        force[a] += magnitude * grad_a;
        force[s] += magnitude * grad_s;
        force[b] += magnitude * grad_b;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bend() -> Bend {
        Bend {
            a: 0,
            s: 1,
            b: 2,
            rest_angle: 0.0,
            stiffness: 0.7,
            damping: 0.0,
            rest_lengths: [1.0, 1.0],
        }
    }

    fn energy(position: &[DVec2]) -> f64 {
        let e1 = position[1] - position[0];
        let e2 = position[2] - position[1];
        0.7 * e1.perp_dot(e2).atan2(e1.dot(e2)).powi(2)
    }

    #[test]
    fn force_is_minus_the_energy_gradient() {
        let position = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.2),
            DVec2::new(1.7, 0.9),
        ];
        let mut force = [DVec2::ZERO; 3];
        add_bending(&[bend()], &position, &[DVec2::ZERO; 3], &mut force);
        let h = 1e-6;
        for i in 0..3 {
            for axis in [DVec2::X, DVec2::Y] {
                let mut plus = position;
                let mut minus = position;
                plus[i] += h * axis;
                minus[i] -= h * axis;
                let numeric = -(energy(&plus) - energy(&minus)) / (2.0 * h);
                assert!((force[i].dot(axis) - numeric).abs() < 1e-7, "particle {i}");
            }
        }
        let total: DVec2 = force.iter().sum();
        assert!(total.length() < 1e-12);
    }
}
