//! Isometric quadratic bending: the 2D counterpart of Bergou et al. 2006 ("A Quadratic
//! Bending Model for Inextensible Surfaces").
//!
//! At a bending vertex s between edges (a, s) and (s, b) with rest lengths ℓ₁, ℓ₂ and
//! rest turning angle θ̄, the bend vector is
//!
//! `d = (x_b − x_s)/ℓ₂ − R(θ̄) (x_s − x_a)/ℓ₁`,
//!
//! the difference of the second edge's tangent and the first's turned by the rest
//! angle. It is linear in the positions, `d = Σ C_j x_j` with constant 2×2 matrices
//! `C_a = R/ℓ₁`, `C_s = −(I/ℓ₂ + R/ℓ₁)`, `C_b = I/ℓ₂`. While the edges keep their rest
//! lengths — the constraints see to it — both tangents are unit vectors and
//! `|d|² = 2 − 2 cos(θ − θ̄)`, which is `(θ − θ̄)²` to fourth order. The energy
//! `K |d|²` is therefore the angle model's `K (θ − θ̄)²` on exact-length
//! configurations, up to that approximation, and it is a quadratic form in the
//! positions with the constant Hessian `2K Jᵀ J`: forces are a sparse matrix–vector
//! product, and an implicit step needs one factorization per topology change (the
//! `implicit_bending` module). Damping `c |ḋ|² / 2` gives the constant matrix `c JᵀJ`.

use bevy::math::{DMat2, DVec2};

use crate::model::Bend;

/// The bend's three constant 2×2 matrices `C_a, C_s, C_b`, with `d = Σ C_j x_j`.
pub fn bend_matrices(bend: &Bend) -> [DMat2; 3] {
    let [first, second] = bend.rest_lengths;
    let turn = DMat2::from_angle(bend.rest_angle);
    let a = turn * (1.0 / first);
    let b = DMat2::IDENTITY * (1.0 / second);
    [a, -(a + b), b]
}

/// The bend vector `d = Σ C_j p_j` of `p` (positions, or velocities for `ḋ`).
pub fn bend_vector(bend: &Bend, matrices: &[DMat2; 3], p: &[DVec2]) -> DVec2 {
    let [a, s, b] = [bend.a, bend.s, bend.b].map(|i| p[i as usize]);
    matrices[0] * a + matrices[1] * s + matrices[2] * b
}

/// The bending energy `Σ K |d|²`.
pub fn quadratic_bending_energy(bends: &[Bend], position: &[DVec2]) -> f64 {
    bends
        .iter()
        .map(|bend| {
            bend.stiffness * bend_vector(bend, &bend_matrices(bend), position).length_squared()
        })
        .sum()
}

/// Add every element's force, `f_j = −C_jᵀ (2K d + c ḋ)` (explicitly: the implicit
/// step of the `implicit_bending` module is how the simulation uses the model).
pub fn add_quadratic_bending(
    bends: &[Bend],
    position: &[DVec2],
    velocity: &[DVec2],
    force: &mut [DVec2],
) {
    for bend in bends {
        let matrices = bend_matrices(bend);
        let d = bend_vector(bend, &matrices, position);
        let rate = bend_vector(bend, &matrices, velocity);
        let pull = -(2.0 * bend.stiffness * d + bend.damping * rate);
        for (i, c) in [bend.a, bend.s, bend.b].into_iter().zip(matrices) {
            force[i as usize] += c.transpose() * pull;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::bending::add_bending;

    fn bend(rest_angle: f64, rest_lengths: [f64; 2]) -> Bend {
        Bend {
            a: 0,
            s: 1,
            b: 2,
            rest_angle,
            stiffness: 0.7,
            damping: 0.0,
            rest_lengths,
        }
    }

    /// Three particles whose edges have exactly the given lengths, turning by `theta`.
    fn exact(lengths: [f64; 2], heading: f64, theta: f64) -> [DVec2; 3] {
        let a = DVec2::new(0.3, -0.2);
        let s = a + lengths[0] * DVec2::from_angle(heading);
        let b = s + lengths[1] * DVec2::from_angle(heading + theta);
        [a, s, b]
    }

    #[test]
    fn force_is_minus_the_energy_gradient() {
        let element = bend(0.4, [0.8, 1.3]);
        let position = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.2),
            DVec2::new(1.7, 0.9),
        ];
        let mut force = [DVec2::ZERO; 3];
        add_quadratic_bending(&[element], &position, &[DVec2::ZERO; 3], &mut force);
        let h = 1e-6;
        for i in 0..3 {
            for axis in [DVec2::X, DVec2::Y] {
                let (mut plus, mut minus) = (position, position);
                plus[i] += h * axis;
                minus[i] -= h * axis;
                let numeric = -(quadratic_bending_energy(&[element], &plus)
                    - quadratic_bending_energy(&[element], &minus))
                    / (2.0 * h);
                assert!((force[i].dot(axis) - numeric).abs() < 1e-7, "particle {i}");
            }
        }
        // Internal forces: no net force (a rigid translation leaves d alone).
        assert!(force.iter().sum::<DVec2>().length() < 1e-12);
    }

    #[test]
    fn energy_is_the_angle_models_on_exact_lengths() {
        for rest_angle in [0.0, 0.3, -1.1] {
            for offset in [1e-3, 0.05, -0.2] {
                let element = bend(rest_angle, [0.05, 0.07]);
                let position = exact(element.rest_lengths, 0.9, rest_angle + offset);
                let quadratic = quadratic_bending_energy(&[element], &position);
                let angle = element.stiffness * offset * offset;
                // |d|² = 2 − 2 cos δ = 4 sin²(δ/2) = δ² (1 − δ²/12 + …); the tangents'
                // rounding (1e-16 of a unit vector) is all that separates them.
                let expected = element.stiffness * 4.0 * (0.5 * offset).sin().powi(2);
                assert!((quadratic - expected).abs() <= 1e-9 * expected);
                assert!((quadratic - angle).abs() <= angle * offset * offset / 12.0 * 1.01);
            }
        }
    }

    #[test]
    fn forces_match_the_angle_model_near_rest() {
        // On an exact-length configuration near the rest angle, the two models' forces
        // agree to the relative order of the angle offset (the quadratic model's
        // tangents turn with the bend; the angle model's gradients are normal to the
        // edges).
        let element = bend(0.25, [0.05, 0.05]);
        let offset = 1e-3;
        let position = exact(element.rest_lengths, -0.4, 0.25 + offset);
        let (mut quadratic, mut angle) = ([DVec2::ZERO; 3], [DVec2::ZERO; 3]);
        add_quadratic_bending(&[element], &position, &[DVec2::ZERO; 3], &mut quadratic);
        add_bending(&[element], &position, &[DVec2::ZERO; 3], &mut angle);
        for (q, a) in quadratic.iter().zip(&angle) {
            assert!((*q - *a).length() <= 2.0 * offset * a.length(), "{q} {a}");
        }
    }
}
