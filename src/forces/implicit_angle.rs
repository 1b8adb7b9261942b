//! Linearly implicit backward Euler for the angle bending model.
//!
//! Explicit angle bending is stable only while `h ω < 2` for its stiffest mode, and
//! that mode's `ω² ∼ k / (m ℓ³)` grows fast as edges shorten: a rope of edges one to
//! two thicknesses long, stable at 1/300 s, gains energy every step at 1/60 s and
//! never comes to rest. Here the bending force and its angle-rate damping are taken at
//! the end of the step, the force linearized at the start:
//! `f(x + h v') ≈ f(x) − h H v'`, with `H` the positive part of the energy's Hessian,
//!
//! `H = 2K g gᵀ + 2K |s| (u₁ u₁ᵀ / ℓ₁² + u₂ u₂ᵀ / ℓ₂²)`, `s = θ − θ̄`, `g = ∂θ/∂x`.
//!
//! The first term is the Gauss–Newton part; the second is the positive half of
//! `2K s ∂²θ/∂x²`, which in each edge vector is `±1/ℓ²` along the directions 45° off
//! the edge (`u₁`, `u₂`, unit in their edge vector): a bend held sharp by a contact
//! needs it — without it, a coil pressed onto itself at 1/60 s never came to rest.
//! Every term is a row `r` of weight `w` (`h c + 2 h² K` for `g`, `2 h² K |s| / ℓ²` for
//! the others), and with `r̂ = √w r` the step is
//!
//! `M v' = M u − R̂ᵀ μ`, `(I + R̂ M⁻¹ R̂ᵀ) μ = R̂ u`,
//!
//! where `u` is the explicit predictor with the bends' elastic force and no bending
//! damping. The matrix is symmetric positive definite (at least the identity, however
//! soft or stiff the bends), and as sparse as rows share particles: banded along a
//! strand, which a sparse LDLᵀ in minimum-degree order factors in linear time. Pinned
//! and kinematic particles (inverse mass 0) keep their velocity and enter through
//! `R̂ u`. The pattern depends on the bends alone: planned once per topology, refilled
//! and factored each step.
//!
//! Only strands that need it pay for it: a strand (a set of bends joined by shared
//! particles) whose stiffest bend's `h² ω²` bound ([`stiffness_number`]) stays below
//! [`IMPLICIT_ABOVE`] keeps the explicit predictor, which is stable there with a
//! margin, and costs a fraction of a solve — a scene at its own step is unchanged by
//! this module. Once a strand is taken implicitly it stays so until the topology
//! changes (a halved step does not re-plan).
//!
//! A pure kernel: slices in, velocities out.

use bevy::math::DVec2;

use super::bending::bend_gradient;
use crate::linalg::SingularPivot;
use crate::linalg::sparse::{SparseFactor, SparsePlan};
use crate::model::Bend;
use crate::model::geometry::{turning_angle, wrap_angle};

/// A bend's rows: the Gauss–Newton row on its three particles, and one curvature row
/// on each edge's two.
const ROWS: usize = 3;

/// The places (0, 1, 2 for a, s, b) each of a bend's rows touches.
const PLACES: [&[u8]; ROWS] = [&[0, 1, 2], &[0, 1], &[1, 2]];

/// Two rows sharing a particle: their entry of the row system.
#[derive(Clone, Copy, Debug)]
struct Coupling {
    /// The two rows (`ROWS * bend + row`, the bend indexing the active bends).
    k: u32,
    l: u32,
    /// The shared particle's place in the bend of each row.
    at_k: u8,
    at_l: u8,
    /// The particle.
    particle: u32,
    /// The entry's value index in the factor.
    slot: u32,
}

/// A strand whose stiffest bend's [`stiffness_number`] reaches this is integrated
/// implicitly. Symplectic Euler is stable below `h² ω² = 4`; a bend's neighbours and
/// its curvature can raise the strand's stiffest mode to a few times one bend's bound.
pub const IMPLICIT_ABOVE: f64 = 0.3;

/// The row system's plan and factor, and its buffers (reused from step to step).
#[derive(Clone, Debug, Default)]
pub struct ImplicitAngle {
    /// Each bend's strand (its bends joined by shared particles), and each strand's
    /// largest [`stiffness_number`] coefficients `(damping, stiffness)`: `h c G` and
    /// `2 h² K G` without their `h` and `h²`.
    strand_of: Vec<u32>,
    strand_coefficients: Vec<(f64, f64)>,
    /// Strands taken implicitly.
    implicit: Vec<bool>,
    /// Bends of the implicit strands with stiffness or damping, as indices into the
    /// topology's bends.
    active: Vec<u32>,
    /// Each row's position in elimination order.
    position: Vec<u32>,
    couplings: Vec<Coupling>,
    plan: SparsePlan,
    factor: SparseFactor,
    /// Each row's scaled vector `r̂` on its bend's particles (a, s, b; zero where the
    /// row does not touch).
    rows: Vec<[DVec2; 3]>,
    rhs: Vec<f64>,
    planned: bool,
}

impl ImplicitAngle {
    /// Find the strands of `bends` (over particles of masses `mass`) and forget which
    /// were implicit: call on every topology change, then [`ImplicitAngle::update`].
    pub fn reset(&mut self, bends: &[Bend], mass: &[f64]) {
        let mut parent: Vec<u32> = (0..mass.len() as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                parent[i as usize] = parent[parent[i as usize] as usize];
                i = parent[i as usize];
            }
            i
        }
        for b in bends {
            for other in [b.a, b.b] {
                let (x, y) = (root(&mut parent, b.s), root(&mut parent, other));
                parent[x.max(y) as usize] = x.min(y);
            }
        }
        let mut number = vec![u32::MAX; mass.len()];
        self.strand_of.clear();
        self.strand_coefficients.clear();
        for b in bends {
            let r = root(&mut parent, b.s) as usize;
            if number[r] == u32::MAX {
                number[r] = self.strand_coefficients.len() as u32;
                self.strand_coefficients.push((0.0, 0.0));
            }
            let strand = number[r];
            self.strand_of.push(strand);
            let (damping, stiffness) = stiffness_number(b, mass);
            let c = &mut self.strand_coefficients[strand as usize];
            *c = (c.0.max(damping), c.1.max(stiffness));
        }
        self.implicit.clear();
        self.implicit.resize(self.strand_coefficients.len(), false);
        self.active.clear();
        self.planned = false;
    }

    /// Take implicitly every strand stiff for the step `dt` (and every strand that
    /// already was), re-planning when that adds one. Returns whether any strand is
    /// implicit.
    pub fn update(&mut self, bends: &[Bend], dt: f64) -> bool {
        let mut added = false;
        for (implicit, &(damping, stiffness)) in
            self.implicit.iter_mut().zip(&self.strand_coefficients)
        {
            if !*implicit && dt * damping + dt * dt * stiffness >= IMPLICIT_ABOVE {
                *implicit = true;
                added = true;
            }
        }
        if added || !self.planned {
            self.plan(bends);
        }
        !self.active.is_empty()
    }

    /// Whether bend `k` (of the bends last reset) is integrated implicitly.
    pub fn is_implicit(&self, k: usize) -> bool {
        self.strand_of
            .get(k)
            .is_some_and(|&strand| self.implicit[strand as usize])
    }

    /// Plan the row system of the implicit strands' bends.
    fn plan(&mut self, bends: &[Bend]) {
        let mut active = std::mem::take(&mut self.active);
        active.clear();
        active.extend((0..bends.len() as u32).filter(|&k| {
            let b = &bends[k as usize];
            self.is_implicit(k as usize) && (b.stiffness > 0.0 || b.damping > 0.0)
        }));
        self.active = active;
        // Rows sharing a particle, found through each particle's rows.
        let mut at: Vec<(u32, u32, u8)> = Vec::with_capacity(7 * self.active.len());
        for (k, &bend) in self.active.iter().enumerate() {
            let b = &bends[bend as usize];
            let ends = [b.a, b.s, b.b];
            for (t, places) in PLACES.iter().enumerate() {
                for &place in *places {
                    let row = (ROWS * k + t) as u32;
                    at.push((ends[place as usize], row, place));
                }
            }
        }
        at.sort_unstable();
        let mut pairs = Vec::new();
        self.couplings.clear();
        let mut start = 0;
        while start < at.len() {
            let end = start
                + at[start..]
                    .iter()
                    .take_while(|t| t.0 == at[start].0)
                    .count();
            for i in start..end {
                for j in i + 1..end {
                    let ((particle, k, at_k), (_, l, at_l)) = (at[i], at[j]);
                    if k == l {
                        continue; // a bend whose ends meet: a degenerate loop of two edges
                    }
                    pairs.push((k, l));
                    self.couplings.push(Coupling {
                        k,
                        l,
                        at_k,
                        at_l,
                        particle,
                        slot: 0,
                    });
                }
            }
            start = end;
        }
        let n = ROWS * self.active.len();
        self.plan = SparsePlan::new(n, &pairs);
        self.position.clear();
        self.position.resize(n, 0);
        for (j, &unknown) in self.plan.order.iter().enumerate() {
            self.position[unknown as usize] = j as u32;
        }
        for c in &mut self.couplings {
            let (i, j) = (
                self.position[c.k as usize] as usize,
                self.position[c.l as usize] as usize,
            );
            c.slot = self
                .plan
                .value_index(i, j)
                .expect("every coupling is in the planned pattern") as u32;
        }
        self.rows.resize(n, [DVec2::ZERO; 3]);
        self.rhs.resize(n, 0.0);
        self.planned = true;
    }

    /// Take the implicit strands' bending damping back out of `force` (it was added
    /// explicitly with every bend's, at the start-of-step `velocity`): the correction
    /// takes it at the end of the step.
    pub fn remove_damping(
        &self,
        bends: &[Bend],
        position: &[DVec2],
        velocity: &[DVec2],
        force: &mut [DVec2],
    ) {
        for &bend in &self.active {
            let b = &bends[bend as usize];
            if b.damping == 0.0 {
                continue;
            }
            let ends = [b.a as usize, b.s as usize, b.b as usize];
            let Some((_, g)) = bend_gradient(b, position) else {
                continue;
            };
            let rate: f64 = ends
                .iter()
                .zip(&g)
                .map(|(&i, gi)| gi.dot(velocity[i]))
                .sum();
            for (&i, gi) in ends.iter().zip(&g) {
                force[i] += b.damping * rate * *gi;
            }
        }
    }

    /// The implicit correction: `velocity` holds `u` (the explicit predictor with the
    /// bends' elastic force and without their damping) and leaves with `v'`; on an
    /// error (a singular system) it is left as it came. `position`
    /// is the start of the step; `bends` those the system was planned for.
    pub fn correct(
        &mut self,
        bends: &[Bend],
        position: &[DVec2],
        velocity: &mut [DVec2],
        inverse_mass: &[f64],
        dt: f64,
    ) -> Result<(), SingularPivot> {
        if self.active.is_empty() {
            return Ok(());
        }
        let plan = &self.plan;
        let values = self.factor.values_mut(plan);
        let w = |i: u32| inverse_mass[i as usize];
        for (k, &bend) in self.active.iter().enumerate() {
            let b = &bends[bend as usize];
            let ends = [b.a, b.s, b.b];
            for (t, row) in bend_rows(b, position, dt).into_iter().enumerate() {
                let r = ROWS * k + t;
                let j = self.position[r] as usize;
                values[j] += 1.0
                    + ends
                        .iter()
                        .zip(&row)
                        .map(|(&i, ri)| w(i) * ri.length_squared())
                        .sum::<f64>();
                // Every row sums to zero over its particles (it does not resist a
                // translation): taken against the middle particle's velocity, a strand
                // moving as one gives exactly zero, however fast.
                let middle = velocity[b.s as usize];
                self.rhs[j] = ends
                    .iter()
                    .zip(&row)
                    .map(|(&i, ri)| ri.dot(velocity[i as usize] - middle))
                    .sum();
                self.rows[r] = row;
            }
        }
        for c in &self.couplings {
            let rk = self.rows[c.k as usize][c.at_k as usize];
            let rl = self.rows[c.l as usize][c.at_l as usize];
            values[c.slot as usize] += w(c.particle) * rk.dot(rl);
        }
        self.factor.factor(plan)?;
        self.factor.solve(plan, &mut self.rhs);
        for (k, &bend) in self.active.iter().enumerate() {
            let b = &bends[bend as usize];
            let ends = [b.a, b.s, b.b];
            for t in 0..ROWS {
                let r = ROWS * k + t;
                let mu = self.rhs[self.position[r] as usize];
                for (&i, ri) in ends.iter().zip(&self.rows[r]) {
                    velocity[i as usize] -= w(i) * mu * *ri;
                }
            }
        }
        Ok(())
    }
}

/// A bound on a bend's `h² ω²` over a step `h`, as coefficients `(c G, 2 K G)` of `h`
/// and `h²`: `G = Σ |∂θ/∂x_i|² / m_i` at its rest lengths, bent or straight.
pub fn stiffness_number(bend: &Bend, mass: &[f64]) -> (f64, f64) {
    let inverse = |i: u32| {
        let m = mass.get(i as usize).copied().unwrap_or(0.0);
        if m > 0.0 { 1.0 / m } else { 0.0 }
    };
    let [l1, l2] = bend.rest_lengths;
    if !(l1 > 0.0 && l2 > 0.0) {
        return (0.0, 0.0);
    }
    let g = inverse(bend.a) / (l1 * l1)
        + inverse(bend.s) * (1.0 / l1 + 1.0 / l2).powi(2)
        + inverse(bend.b) / (l2 * l2);
    (bend.damping * g, 2.0 * bend.stiffness * g)
}

/// A bend's scaled rows `√w r` on (a, s, b) at `position` over a step `dt`: zero for a
/// bend with an edge of zero length.
fn bend_rows(bend: &Bend, position: &[DVec2], dt: f64) -> [[DVec2; 3]; ROWS] {
    let Some(([e1, e2], [ga, gs, gb])) = bend_gradient(bend, position) else {
        return [[DVec2::ZERO; 3]; ROWS];
    };
    let (l1, l2) = (e1.length_squared(), e2.length_squared());
    let gauss_newton = (dt * bend.damping + 2.0 * dt * dt * bend.stiffness).sqrt();
    let bent = wrap_angle(turning_angle(e1, e2) - bend.rest_angle);
    // The positive half of 2K s ∂²φ/∂e²: φ(e) = atan2(e) has ±1/|e|² along the
    // directions 45° off e; θ = φ₂ − φ₁.
    let curvature = (2.0 * dt * dt * bend.stiffness * bent.abs()).sqrt();
    let turn = DVec2::from_angle(std::f64::consts::FRAC_PI_4 * bent.signum());
    let u1 = curvature * turn.rotate(e1) / l1;
    let u2 = curvature * DVec2::new(turn.x, -turn.y).rotate(e2) / l2;
    [
        [gauss_newton * ga, gauss_newton * gs, gauss_newton * gb],
        [-u1, u1, DVec2::ZERO],
        [DVec2::ZERO, -u2, u2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A curled chain of six particles, the first pinned, with unequal masses, rest
    /// lengths and rest angles: bends, positions, velocities, inverse masses.
    fn chain() -> (Vec<Bend>, Vec<DVec2>, Vec<DVec2>, Vec<f64>) {
        let position: Vec<DVec2> = (0..6)
            .map(|i| {
                let t = i as f64;
                DVec2::new(0.1 * t + 0.01 * t * t, 0.04 * (1.7 * t).sin())
            })
            .collect();
        let velocity = (0..6)
            .map(|i| DVec2::new(0.2 * (i as f64).cos(), -0.1 * i as f64))
            .collect();
        let mut inverse_mass: Vec<f64> = [1.0, 0.5, 2.0, 1.5, 0.7, 1.1]
            .iter()
            .map(|m| 1.0 / m)
            .collect();
        inverse_mass[0] = 0.0;
        let bends = (1..5)
            .map(|s| Bend {
                a: s - 1,
                s,
                b: s + 1,
                rest_angle: 0.4 * s as f64 - 0.9,
                stiffness: 3.0 + s as f64,
                damping: 0.05 * s as f64,
                rest_lengths: [0.1, 0.1],
            })
            .collect();
        (bends, position, velocity, inverse_mass)
    }

    /// `(M + Σ r̂ r̂ᵀ) v' = M u` over the free particles, solved densely.
    #[allow(clippy::needless_range_loop)] // Gaussian elimination by indices
    fn dense(
        bends: &[Bend],
        position: &[DVec2],
        velocity: &[DVec2],
        inverse_mass: &[f64],
        dt: f64,
    ) -> Vec<DVec2> {
        let n = position.len();
        let mut a = vec![vec![0.0; 2 * n]; 2 * n];
        let mut rhs = vec![0.0; 2 * n];
        for i in 0..n {
            for c in 0..2 {
                // A pinned particle's row just keeps its velocity.
                let m = if inverse_mass[i] > 0.0 {
                    1.0 / inverse_mass[i]
                } else {
                    1.0
                };
                a[2 * i + c][2 * i + c] = m;
                rhs[2 * i + c] = m * velocity[i][c];
            }
        }
        for b in bends {
            let ends = [b.a as usize, b.s as usize, b.b as usize];
            for row in bend_rows(b, position, dt) {
                for (p, rp) in ends.iter().zip(&row) {
                    if inverse_mass[*p] == 0.0 {
                        continue;
                    }
                    for (q, rq) in ends.iter().zip(&row) {
                        for (c, d) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                            if inverse_mass[*q] > 0.0 {
                                a[2 * p + c][2 * q + d] += rp[c] * rq[d];
                            } else {
                                rhs[2 * p + c] -= rp[c] * rq[d] * velocity[*q][d];
                            }
                        }
                    }
                }
            }
        }
        // Gaussian elimination (the matrix is SPD; no pivoting needed).
        for k in 0..2 * n {
            for i in k + 1..2 * n {
                let f = a[i][k] / a[k][k];
                for j in k..2 * n {
                    a[i][j] -= f * a[k][j];
                }
                rhs[i] -= f * rhs[k];
            }
        }
        let mut x = vec![0.0; 2 * n];
        for k in (0..2 * n).rev() {
            let tail: f64 = (k + 1..2 * n).map(|j| a[k][j] * x[j]).sum();
            x[k] = (rhs[k] - tail) / a[k][k];
        }
        (0..n).map(|i| DVec2::new(x[2 * i], x[2 * i + 1])).collect()
    }

    #[test]
    fn the_row_system_matches_a_dense_solve() {
        let (bends, position, velocity, inverse_mass) = chain();
        for dt in [1e-3, 1.0 / 60.0, 0.5] {
            let mut solver = ImplicitAngle::default();
            solver.reset(&bends, &[1.0; 6]);
            solver.implicit.fill(true);
            solver.plan(&bends);
            let mut next = velocity.clone();
            solver
                .correct(&bends, &position, &mut next, &inverse_mass, dt)
                .unwrap();
            let expected = dense(&bends, &position, &velocity, &inverse_mass, dt);
            assert_eq!(
                next[0], velocity[0],
                "the pinned particle keeps its velocity"
            );
            for (i, (got, want)) in next.iter().zip(&expected).enumerate() {
                assert!(
                    (*got - *want).length() < 1e-10,
                    "dt {dt}, particle {i}: {got} vs {want}"
                );
            }
        }
    }

    /// The energy `K (θ − θ̄)²` of one bend at `x` (a, s, b).
    fn energy(bend: &Bend, x: &[DVec2; 3]) -> f64 {
        let theta = turning_angle(x[1] - x[0], x[2] - x[1]);
        bend.stiffness * wrap_angle(theta - bend.rest_angle).powi(2)
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // a 6 × 6 matrix filled by its indices
    fn the_rows_hold_the_positive_part_of_the_hessian() {
        // Finite differences of the energy against the rows' Σ r̂ r̂ᵀ / h² (no damping):
        // their difference must be positive semi-definite (the rows cover every
        // positive curvature), and their trace must be the Hessian's positive part's.
        let dt = 0.01;
        for (rest, stiffness) in [(0.0, 1.0), (-0.7, 2.0), (1.2, 0.5), (2.9, 1.0)] {
            let bend = Bend {
                a: 0,
                s: 1,
                b: 2,
                rest_angle: rest,
                stiffness,
                damping: 0.0,
                rest_lengths: [1.0, 1.0],
            };
            let x = [
                DVec2::new(0.0, 0.0),
                DVec2::new(0.9, 0.1),
                DVec2::new(1.3, 0.8),
            ];
            let rows = bend_rows(&bend, &x, dt);
            let mut cover = [[0.0; 6]; 6];
            for row in &rows {
                for i in 0..6 {
                    for j in 0..6 {
                        cover[i][j] += row[i / 2][i % 2] * row[j / 2][j % 2] / (dt * dt);
                    }
                }
            }
            let step = 1e-4;
            let at = |d: &[(usize, f64)]| {
                let mut y = x;
                for &(k, v) in d {
                    y[k / 2][k % 2] += v;
                }
                energy(&bend, &y)
            };
            let mut hessian = [[0.0; 6]; 6];
            for i in 0..6 {
                for j in 0..6 {
                    hessian[i][j] = (at(&[(i, step), (j, step)])
                        - at(&[(i, step), (j, -step)])
                        - at(&[(i, -step), (j, step)])
                        + at(&[(i, -step), (j, -step)]))
                        / (4.0 * step * step);
                }
            }
            // Every direction: vᵀ (cover − H) v ≥ 0, on random directions.
            let mut seed = 7u64;
            for _ in 0..2000 {
                let v: Vec<f64> = (0..6)
                    .map(|_| {
                        seed = seed
                            .wrapping_mul(6364136223846793005)
                            .wrapping_add(1442695040888963407);
                        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
                    })
                    .collect();
                let q = |m: &[[f64; 6]; 6]| -> f64 {
                    (0..6)
                        .map(|i| (0..6).map(|j| v[i] * m[i][j] * v[j]).sum::<f64>())
                        .sum()
                };
                assert!(
                    q(&cover) - q(&hessian) > -1e-5 * q(&cover).abs().max(1.0),
                    "rest {rest}: the rows miss a positive curvature"
                );
            }
        }
    }

    #[test]
    fn a_stiff_curled_chain_stays_bounded_at_a_game_step() {
        // A thousand times stiffer than the explicit step could take, curled away from
        // its rest shape: its kinetic energy never grows past what the bends held.
        let (mut bends, mut position, mut velocity, inverse_mass) = chain();
        for bend in &mut bends {
            bend.stiffness *= 1e3;
            bend.damping = 0.0;
        }
        velocity.iter_mut().for_each(|v| *v = DVec2::ZERO);
        let held: f64 = bends
            .iter()
            .map(|b| {
                energy(
                    b,
                    &[
                        position[b.a as usize],
                        position[b.s as usize],
                        position[b.b as usize],
                    ],
                )
            })
            .sum();
        let dt = 1.0 / 60.0;
        let mut solver = ImplicitAngle::default();
        solver.reset(&bends, &[1.0, 0.5, 2.0, 1.5, 0.7, 1.1]);
        assert!(
            solver.update(&bends, dt),
            "this chain is stiff for the step"
        );
        let mut force = vec![DVec2::ZERO; position.len()];
        for _ in 0..600 {
            force.iter_mut().for_each(|f| *f = DVec2::ZERO);
            crate::forces::bending::add_bending(&bends, &position, &[DVec2::ZERO; 6], &mut force);
            for ((v, f), w) in velocity.iter_mut().zip(&force).zip(&inverse_mass) {
                *v += dt * w * *f;
            }
            solver
                .correct(&bends, &position, &mut velocity, &inverse_mass, dt)
                .unwrap();
            for (x, v) in position.iter_mut().zip(&velocity) {
                *x += dt * *v;
            }
            let kinetic: f64 = velocity
                .iter()
                .zip(&inverse_mass)
                .filter(|(_, w)| **w > 0.0)
                .map(|(v, w)| 0.5 * v.length_squared() / w)
                .sum();
            assert!(kinetic.is_finite() && kinetic <= held, "{kinetic} > {held}");
        }
    }
}
