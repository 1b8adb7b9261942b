//! Backward Euler for the quadratic bending model.
//!
//! The model's force is linear with constant matrices, `f_b = −K x − C v` with
//! `K = Σ 2k JᵀJ` and `C = Σ c JᵀJ` ([`super::quadratic_bending`]). Backward Euler
//! evaluates it at the end of the step, `M (v' − v) = h (f + f_b(x + h v', v'))`, so
//!
//! `(M + h C + h² K) v' = M v + h f − h K x`,
//!
//! with `f` every other force, taken explicitly as before. The matrix depends on the
//! bends, the masses and the step only: it is assembled and factored (sparse LDLᵀ,
//! minimum-degree order — a strand's system is banded) once per change of those, and
//! each step costs one sparse solve. Unknowns are the free particles of the bends;
//! pinned and kinematic ones keep their prescribed velocity, which enters the
//! right-hand side. Free particles in no bend take the explicit predictor.
//!
//! Stiff bending is then stable at any step — the implicit step damps the modes it
//! cannot resolve rather than amplifying them — where the explicit angle model needs
//! `h < 2 / ω` of its stiffest mode.

use bevy::math::{DMat2, DVec2};

use super::quadratic_bending::{bend_matrices, bend_vector};
use crate::linalg::SingularPivot;
use crate::linalg::sparse::{SparseFactor, SparsePlan};
use crate::model::Bend;

const NONE: u32 = u32::MAX;

/// The factored implicit bending system and what it was built from.
#[derive(Clone, Debug, Default)]
pub struct ImplicitBending {
    /// Unknown number of each particle (two coordinates each), `u32::MAX` for none.
    unknown_of: Vec<u32>,
    /// Particle of each unknown particle.
    particles: Vec<u32>,
    /// The masses and the step the factor holds.
    masses: Vec<f64>,
    dt: f64,
    /// Each bend's matrices `C_a, C_s, C_b` (a rotation by the rest angle: computed
    /// once, not every step) and its weight `h c + 2 h² k`.
    matrices: Vec<[DMat2; 3]>,
    weights: Vec<f64>,
    plan: SparsePlan,
    factor: SparseFactor,
    /// Right-hand side, in elimination order.
    rhs: Vec<f64>,
    /// Right-hand side by unknown coordinate.
    gathered: Vec<f64>,
    built: bool,
}

impl ImplicitBending {
    /// Whether the factor was built for these masses and this step (the caller tracks
    /// the bends: rebuild on every topology change).
    pub fn is_current(&self, mass: &[f64], dt: f64) -> bool {
        self.built
            && self.dt == dt
            && self.particles.len() == self.masses.len()
            && self
                .particles
                .iter()
                .zip(&self.masses)
                .all(|(&p, &m)| mass.get(p as usize) == Some(&m))
    }

    /// Assemble and factor `M + h C + h² K` for `bends` over the particles with a
    /// non-zero inverse mass.
    pub fn build(
        &mut self,
        bends: &[Bend],
        mass: &[f64],
        inverse_mass: &[f64],
        dt: f64,
    ) -> Result<(), SingularPivot> {
        self.built = false;
        let free = |i: u32| inverse_mass.get(i as usize).is_some_and(|&w| w > 0.0);
        self.unknown_of.clear();
        self.unknown_of.resize(mass.len(), NONE);
        self.particles.clear();
        for bend in bends {
            for i in [bend.a, bend.s, bend.b] {
                if free(i) && self.unknown_of[i as usize] == NONE {
                    self.unknown_of[i as usize] = self.particles.len() as u32;
                    self.particles.push(i);
                }
            }
        }
        self.masses.clear();
        self.masses
            .extend(self.particles.iter().map(|&p| mass[p as usize]));
        self.dt = dt;
        self.matrices.clear();
        self.matrices.extend(bends.iter().map(bend_matrices));
        self.weights.clear();
        self.weights.extend(
            bends
                .iter()
                .map(|b| dt * b.damping + 2.0 * dt * dt * b.stiffness),
        );

        // Every block, and every coupled pair of coordinates in them (a zero entry is
        // left out, so that a straight rest shape keeps x and y apart).
        let mut blocks = Vec::new();
        self.for_each_block(bends, |entry| blocks.push(entry));
        let entries = |&(u, v, block): &(u32, u32, DMat2)| {
            [(0, 0), (0, 1), (1, 0), (1, 1)]
                .into_iter()
                .map(move |(r, c)| (2 * u + r, 2 * v + c, block.col(c as usize)[r as usize]))
                .filter(|&(.., value)| value != 0.0)
        };
        let pairs: Vec<(u32, u32)> = blocks
            .iter()
            .flat_map(entries)
            .map(|(i, j, _)| (i, j))
            .collect();
        let n = 2 * self.particles.len();
        self.plan = SparsePlan::new(n, &pairs);
        let mut position = vec![0u32; n];
        for (j, &unknown) in self.plan.order.iter().enumerate() {
            position[unknown as usize] = j as u32;
        }
        let plan = &self.plan;
        let values = self.factor.values_mut(plan);
        for (k, &m) in self.masses.iter().enumerate() {
            for r in 0..2 {
                values[position[2 * k + r] as usize] += m;
            }
        }
        let mut add = |i: u32, j: u32, value: f64| {
            let (i, j) = (position[i as usize] as usize, position[j as usize] as usize);
            // The lower triangle holds each symmetric pair once.
            if i >= j
                && let Some(slot) = plan.value_index(i, j)
            {
                values[slot] += value;
            }
        };
        for (i, j, value) in blocks.iter().flat_map(entries) {
            add(i, j, value);
        }
        self.factor.factor(&self.plan)?;
        self.rhs.resize(n, 0.0);
        self.gathered.resize(n, 0.0);
        self.built = true;
        Ok(())
    }

    /// Every block `(h c + 2 h² k) C_iᵀ C_j` between unknown particles of a bend.
    fn for_each_block(&self, bends: &[Bend], mut visit: impl FnMut((u32, u32, DMat2))) {
        for ((bend, matrices), &weight) in bends.iter().zip(&self.matrices).zip(&self.weights) {
            let ends = [bend.a, bend.s, bend.b];
            for (i, ci) in ends.iter().zip(matrices) {
                let u = self.unknown_of[*i as usize];
                if u == NONE {
                    continue;
                }
                for (j, cj) in ends.iter().zip(matrices) {
                    let v = self.unknown_of[*j as usize];
                    if v != NONE {
                        visit((u, v, ci.transpose() * *cj * weight));
                    }
                }
            }
        }
    }

    /// The predictor with implicit bending: `velocity` from the step's start to its
    /// candidate, `force` holding every force but bending. `bends` are those the
    /// system was built for.
    pub fn predict(
        &mut self,
        bends: &[Bend],
        position: &[DVec2],
        velocity: &mut [DVec2],
        force: &[DVec2],
        inverse_mass: &[f64],
    ) {
        let dt = self.dt;
        // M v + h f for the unknowns; the explicit predictor for every other free
        // particle (pinned ones have inverse mass 0 and keep their velocity).
        for (i, ((v, &f), &w)) in velocity.iter_mut().zip(force).zip(inverse_mass).enumerate() {
            let u = self.unknown_of.get(i).copied().unwrap_or(NONE);
            if u == NONE {
                *v += dt * w * f;
            } else {
                let momentum = self.masses[u as usize] * *v + dt * f;
                self.gathered[2 * u as usize] = momentum.x;
                self.gathered[2 * u as usize + 1] = momentum.y;
            }
        }
        // − h K x, and the pinned particles' prescribed velocities moved to the right.
        debug_assert_eq!(bends.len(), self.matrices.len(), "built for other bends");
        for ((bend, matrices), &weight) in bends.iter().zip(&self.matrices).zip(&self.weights) {
            let ends = [bend.a, bend.s, bend.b];
            let d = bend_vector(bend, matrices, position);
            let mut pinned_rate = DVec2::ZERO;
            for (&j, c) in ends.iter().zip(matrices) {
                if self.unknown_of[j as usize] == NONE {
                    pinned_rate += *c * velocity[j as usize];
                }
            }
            let pull = -2.0 * dt * bend.stiffness * d - weight * pinned_rate;
            for (&i, c) in ends.iter().zip(matrices) {
                let u = self.unknown_of[i as usize];
                if u != NONE {
                    let add = c.transpose() * pull;
                    self.gathered[2 * u as usize] += add.x;
                    self.gathered[2 * u as usize + 1] += add.y;
                }
            }
        }
        for (j, &unknown) in self.plan.order.iter().enumerate() {
            self.rhs[j] = self.gathered[unknown as usize];
        }
        self.factor.solve(&self.plan, &mut self.rhs);
        for (j, &unknown) in self.plan.order.iter().enumerate() {
            self.gathered[unknown as usize] = self.rhs[j];
        }
        for (k, &p) in self.particles.iter().enumerate() {
            velocity[p as usize] = DVec2::new(self.gathered[2 * k], self.gathered[2 * k + 1]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::quadratic_bending::add_quadratic_bending;

    type Chain = (Vec<Bend>, Vec<DVec2>, Vec<DVec2>, Vec<f64>, Vec<f64>);

    /// A curled chain of six particles, the first pinned and moving (kinematic), with
    /// unequal masses, rest lengths and rest angles: bends, positions, velocities,
    /// masses and inverse masses.
    fn chain() -> Chain {
        let position: Vec<DVec2> = (0..6)
            .map(|i| {
                let t = i as f64;
                DVec2::new(0.1 * t + 0.01 * t * t, 0.03 * (1.7 * t).sin())
            })
            .collect();
        let velocity: Vec<DVec2> = (0..6)
            .map(|i| DVec2::new(0.2 * (i as f64).cos(), -0.1 * i as f64))
            .collect();
        let mass = vec![1.0, 0.5, 2.0, 1.5, 0.7, 1.1];
        let mut inverse_mass: Vec<f64> = mass.iter().map(|m| 1.0 / m).collect();
        inverse_mass[0] = 0.0;
        let bends = (1..5)
            .map(|s| Bend {
                a: s - 1,
                s,
                b: s + 1,
                rest_angle: 0.2 * s as f64 - 0.3,
                stiffness: 3.0 + s as f64,
                damping: 0.05 * s as f64,
                rest_lengths: [0.1 + 0.01 * s as f64, 0.12],
            })
            .collect();
        (bends, position, velocity, mass, inverse_mass)
    }

    #[test]
    fn the_step_is_backward_euler() {
        let (bends, position, velocity, mass, inverse_mass) = chain();
        let force: Vec<DVec2> = (0..6).map(|i| DVec2::new(0.3, -9.81 * mass[i])).collect();
        let dt = 0.01;
        let mut solver = ImplicitBending::default();
        solver.build(&bends, &mass, &inverse_mass, dt).unwrap();
        assert!(solver.is_current(&mass, dt));
        assert!(!solver.is_current(&mass, 0.02));
        let mut next = velocity.clone();
        solver.predict(&bends, &position, &mut next, &force, &inverse_mass);
        // M (v' − v) = h (f + f_b(x + h v', v')) for every free particle.
        let end: Vec<DVec2> = position
            .iter()
            .zip(&next)
            .map(|(x, v)| *x + dt * *v)
            .collect();
        let mut total = force.clone();
        add_quadratic_bending(&bends, &end, &next, &mut total);
        assert_eq!(
            next[0], velocity[0],
            "the kinematic particle keeps its velocity"
        );
        for i in 1..6 {
            let residual = mass[i] * (next[i] - velocity[i]) - dt * total[i];
            assert!(residual.length() < 1e-12, "particle {i}: {residual}");
        }
    }

    #[test]
    fn very_stiff_bending_stays_bounded_at_a_large_step() {
        // 10⁶ times stiffer than the explicit step could take: the implicit step
        // dissipates the bend instead of amplifying it.
        let (mut bends, mut position, mut velocity, mass, inverse_mass) = chain();
        for bend in &mut bends {
            bend.stiffness *= 1e6;
        }
        let dt = 1.0 / 60.0;
        let force = vec![DVec2::ZERO; 6];
        let mut solver = ImplicitBending::default();
        solver.build(&bends, &mass, &inverse_mass, dt).unwrap();
        let initial = crate::forces::quadratic_bending::quadratic_bending_energy(&bends, &position);
        for _ in 0..200 {
            velocity[0] = DVec2::ZERO;
            solver.predict(&bends, &position, &mut velocity, &force, &inverse_mass);
            for (x, v) in position.iter_mut().zip(&velocity) {
                *x += dt * *v;
            }
        }
        let energy = crate::forces::quadratic_bending::quadratic_bending_energy(&bends, &position);
        assert!(
            energy.is_finite() && energy <= initial,
            "{initial} -> {energy}"
        );
    }
}
