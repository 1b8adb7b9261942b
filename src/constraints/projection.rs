//! Fast projection of a chain island (a path or a loop) onto its length constraints.
//!
//! Per edge k from a to b, `C_k(x) = |x_b − x_a|² − L_k²`. Starting from the
//! unconstrained end of step `x̃ = x + dt v*`, repeat: solve `A δ = −C(x̃)` with
//! `A = J(x̃) W Dᵀ`, move `x̃ += W Dᵀ δ`, until `max |C_k| / L_k²` is below the tolerance
//! or the iteration cap is hit; then `v = (x̃ − x) / dt` (Goldenthal et al. 2007).
//! The kernel carries `x̃ − x − dt v*` rather than `x̃` itself, and forms edges from
//! coordinate differences: the result is the same in exact arithmetic, but in f64 the
//! residual is then resolved relative to each edge's own length wherever the strand
//! is, and the velocity change is exactly the impulses (momentum to round-off).
//!
//! `D` holds the constraint directions. At the latest iterate (`D = J(x̃)`), `A` is
//! symmetric positive definite: the fast-projection approximation of the implicit
//! constraint direction. At the start of the step (`D = J(x)`, as in SHAKE), the
//! impulses act along the edges the particles sit on, so they exert no torque and
//! angular momentum is conserved exactly; `A` is then not symmetric but still
//! tridiagonal. Either way linear momentum is conserved: each edge's impulse pair is
//! equal and opposite. The price of the fixed direction: when a step moves an edge by
//! a sizeable fraction of its length sideways, no impulse along the old edge can
//! restore the length, and the iteration stalls (SHAKE's known failure); the
//! end-of-step direction has no such limit.
//!
//! A pure kernel: slices in, slices out, no allocation once the scratch is sized.

use bevy::math::DVec2;
use bevy::prelude::Reflect;

use super::cyclic::{CyclicScratch, solve_cyclic_tridiagonal};
use super::islands::IslandEdge;
use super::tridiagonal::solve_tridiagonal;

/// Where the constraint direction is evaluated (DESIGN §5).
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ConstraintDirection {
    /// At the latest iterate: fast projection, a symmetric system.
    #[default]
    EndOfStep,
    /// At the start of the step: torque-free impulses, angular momentum conserved.
    StartOfStep,
}

/// Stopping rule of the projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionSettings {
    /// Stop when every `|C_k| / L_k²` (≈ twice the relative length error) is at most this.
    pub tolerance: f64,
    /// Stop after this many linear solves even if the tolerance is not met.
    pub max_iterations: u32,
    /// Where the constraint direction is evaluated.
    pub direction: ConstraintDirection,
}

/// How a projection ended.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProjectionOutcome {
    /// Linear solves performed.
    pub iterations: u32,
    /// Whether the tolerance was met.
    pub converged: bool,
    /// Final `max |C_k| / L_k²`.
    pub residual: f64,
    /// Whether a linear solve met a singular system (an edge of zero length); the
    /// velocities are then left as the last good iterate gives them.
    pub singular: bool,
}

/// Reusable buffers for [`project_chain`], sized by [`ChainScratch::reserve`].
#[derive(Clone, Debug, Default)]
pub struct ChainScratch {
    correction: Vec<DVec2>,
    inverse_mass: Vec<f64>,
    predicted_edge: Vec<DVec2>,
    edge: Vec<DVec2>,
    start_direction: Vec<DVec2>,
    constraint: Vec<f64>,
    lower: Vec<f64>,
    diagonal: Vec<f64>,
    upper: Vec<f64>,
    rhs: Vec<f64>,
    thomas: Vec<f64>,
    cyclic: CyclicScratch,
}

impl ChainScratch {
    /// Make room for chains of up to `edges` edges (allocates only when growing).
    pub fn reserve(&mut self, edges: usize) {
        let particles = edges + 1;
        grow(&mut self.correction, particles, DVec2::ZERO);
        grow(&mut self.inverse_mass, particles, 0.0);
        grow(&mut self.predicted_edge, edges, DVec2::ZERO);
        grow(&mut self.edge, edges, DVec2::ZERO);
        grow(&mut self.start_direction, edges, DVec2::ZERO);
        for buffer in [
            &mut self.constraint,
            &mut self.lower,
            &mut self.diagonal,
            &mut self.upper,
            &mut self.rhs,
            &mut self.thomas,
        ] {
            grow(buffer, edges, 0.0);
        }
        self.cyclic.reserve(edges);
    }
}

fn grow<T: Clone>(buffer: &mut Vec<T>, n: usize, value: T) {
    if buffer.len() < n {
        buffer.resize(n, value);
    }
}

/// The smallest `|C| / L²` asked for whatever the tolerance: edges are formed from
/// coordinate differences, so f64 resolves them to a few ulps of their own length and
/// asking for less would only spin.
pub const ROUND_OFF_FLOOR: f64 = 16.0 * f64::EPSILON;

/// A path or loop island: its edges in walking order (edge k + 1 starts where edge k
/// ends; when `closed`, the last ends where the first starts).
#[derive(Clone, Copy, Debug)]
pub struct Chain<'a> {
    /// The edges, in order.
    pub edges: &'a [IslandEdge],
    /// Whether the chain is a loop.
    pub closed: bool,
}

/// Project the velocities of one chain so that every edge ends the step at its rest
/// length. Returns how the iteration ended; on a singular system the corrections found
/// so far are applied. Only free particles' entries of `velocity` change.
pub fn project_chain(
    chain: Chain,
    position: &[DVec2],
    velocity: &mut [DVec2],
    inverse_mass: &[f64],
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut ChainScratch,
) -> ProjectionOutcome {
    let Chain { edges, closed } = chain;
    let m = edges.len();
    if m == 0 {
        return ProjectionOutcome {
            converged: true,
            ..Default::default()
        };
    }
    scratch.reserve(m);
    let particles = if closed { m } else { m + 1 };
    let particle = |j: usize| if j < m { edges[j].a } else { edges[m - 1].b } as usize;
    let next = |k: usize| if k + 1 == particles { 0 } else { k + 1 };
    let ChainScratch {
        correction,
        inverse_mass: w,
        predicted_edge,
        edge,
        start_direction,
        constraint,
        lower,
        diagonal,
        upper,
        rhs,
        thomas,
        cyclic,
    } = scratch;

    // Iterate on the correction Δ to the predicted motion, x̃ = x + dt v* + Δ, and on
    // edges formed from differences, so that nothing depends on the distance from the
    // origin and v = v* + Δ / dt changes the momentum only by the impulses.
    for j in 0..particles {
        correction[j] = DVec2::ZERO;
        w[j] = inverse_mass[particle(j)];
    }
    for (k, e) in edges.iter().enumerate() {
        let (a, b) = (e.a as usize, e.b as usize);
        start_direction[k] = position[b] - position[a];
        predicted_edge[k] = start_direction[k] + dt * (velocity[b] - velocity[a]);
    }

    let mut outcome = ProjectionOutcome::default();
    loop {
        let mut residual = 0.0f64;
        for k in 0..m {
            edge[k] = predicted_edge[k] + (correction[next(k)] - correction[k]);
            let rest_squared = edges[k].rest_length * edges[k].rest_length;
            constraint[k] = edge[k].length_squared() - rest_squared;
            residual = residual.max(constraint[k].abs() / rest_squared);
        }
        outcome.residual = residual;
        if residual <= settings.tolerance.max(ROUND_OFF_FLOOR) {
            outcome.converged = true;
            break;
        }
        if outcome.iterations >= settings.max_iterations {
            break;
        }
        outcome.iterations += 1;

        let direction: &[DVec2] = match settings.direction {
            ConstraintDirection::EndOfStep => &edge[..m],
            ConstraintDirection::StartOfStep => &start_direction[..m],
        };
        for k in 0..m {
            let (s_prev, s_next) = (k, next(k));
            let prev_edge = if k == 0 { m - 1 } else { k - 1 };
            let next_edge = if k + 1 == m { 0 } else { k + 1 };
            diagonal[k] = 4.0 * (w[s_prev] + w[s_next]) * edge[k].dot(direction[k]);
            lower[k] = -4.0 * w[s_prev] * edge[k].dot(direction[prev_edge]);
            upper[k] = -4.0 * w[s_next] * edge[k].dot(direction[next_edge]);
            rhs[k] = -constraint[k];
        }
        let solved = if closed && m >= 3 {
            solve_cyclic_tridiagonal(
                &lower[..m],
                &diagonal[..m],
                &upper[..m],
                &mut rhs[..m],
                cyclic,
            )
        } else {
            // An open chain's first and last rows have no outer neighbours.
            lower[0] = 0.0;
            upper[m - 1] = 0.0;
            solve_tridiagonal(
                &lower[..m],
                &diagonal[..m],
                &upper[..m],
                &mut rhs[..m],
                &mut thomas[..m],
            )
        };
        if solved.is_err() {
            outcome.singular = true;
            break;
        }
        for k in 0..m {
            let impulse = 2.0 * rhs[k] * direction[k];
            correction[k] -= w[k] * impulse;
            let b = next(k);
            correction[b] += w[b] * impulse;
        }
    }

    for j in 0..particles {
        if w[j] > 0.0 {
            velocity[particle(j)] += correction[j] / dt;
        }
    }
    outcome
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    fn chain_edges(points: &[DVec2], closed: bool) -> Vec<IslandEdge> {
        let n = points.len();
        let m = if closed { n } else { n - 1 };
        (0..m)
            .map(|k| IslandEdge {
                a: k as u32,
                b: ((k + 1) % n) as u32,
                rest_length: points[k].distance(points[(k + 1) % n]),
                edge: k as u32,
            })
            .collect()
    }

    fn settings(direction: ConstraintDirection) -> ProjectionSettings {
        ProjectionSettings {
            tolerance: 1e-13,
            max_iterations: 50,
            direction,
        }
    }

    fn max_relative_error(
        edges: &[IslandEdge],
        position: &[DVec2],
        velocity: &[DVec2],
        dt: f64,
    ) -> f64 {
        edges
            .iter()
            .map(|e| {
                let (a, b) = (e.a as usize, e.b as usize);
                let length =
                    (position[b] + dt * velocity[b]).distance(position[a] + dt * velocity[a]);
                (length - e.rest_length).abs() / e.rest_length
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn random_chains_end_the_step_at_rest_length() {
        let mut rng = StdRng::seed_from_u64(3);
        for trial in 0..40 {
            let closed = trial % 4 == 3;
            let n = rng.random_range(3..80);
            let mut points = vec![DVec2::new(0.5, 0.5)];
            let mut heading: f64 = 0.0;
            for _ in 1..n {
                heading += rng.random_range(-0.8..0.8);
                let step = rng.random_range(0.005..0.03);
                points.push(*points.last().unwrap() + step * DVec2::from_angle(heading));
            }
            if closed {
                // A regular polygon instead, so the loop closes.
                let radius = 0.1;
                points = (0..n)
                    .map(|i| {
                        DVec2::new(0.5, 0.5)
                            + radius
                                * DVec2::from_angle(std::f64::consts::TAU * i as f64 / n as f64)
                    })
                    .collect();
            }
            let edges = chain_edges(&points, closed);
            let speed = if trial % 2 == 0 { 1.0 } else { 3.0 };
            let mut velocity: Vec<DVec2> = (0..n)
                .map(|_| {
                    speed * DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                })
                .collect();
            let mut inverse_mass: Vec<f64> =
                (0..n).map(|_| 1.0 / rng.random_range(0.1..10.0)).collect();
            if trial % 3 == 1 {
                inverse_mass[0] = 0.0; // pinned end
                velocity[0] = DVec2::ZERO;
            }
            let momentum_before: DVec2 = (0..n)
                .filter(|&i| inverse_mass[i] > 0.0)
                .map(|i| velocity[i] / inverse_mass[i])
                .sum();
            // Start-of-step directions (SHAKE) need small displacements: see the module doc.
            let directions: &[ConstraintDirection] = if speed <= 1.0 {
                &[
                    ConstraintDirection::EndOfStep,
                    ConstraintDirection::StartOfStep,
                ]
            } else {
                &[ConstraintDirection::EndOfStep]
            };
            for &direction in directions {
                let mut v = velocity.clone();
                let dt = 1.0 / 3000.0;
                let outcome = project_chain(
                    Chain {
                        edges: &edges,
                        closed,
                    },
                    &points,
                    &mut v,
                    &inverse_mass,
                    dt,
                    &settings(direction),
                    &mut ChainScratch::default(),
                );
                assert!(
                    outcome.converged,
                    "trial {trial} {direction:?}: {outcome:?}"
                );
                // Up to ~5 % of an edge per step converges fast; the extreme trials move
                // edges by up to 20 % and only need to converge within the default cap.
                let cap = if speed <= 1.0 { 6 } else { 20 };
                assert!(outcome.iterations <= cap, "trial {trial}: {outcome:?}");
                let error = max_relative_error(&edges, &points, &v, dt);
                assert!(error < 1e-12, "trial {trial} {direction:?}: {error}");
                if inverse_mass[0] > 0.0 {
                    let momentum: DVec2 = (0..n).map(|i| v[i] / inverse_mass[i]).sum();
                    assert!(
                        (momentum - momentum_before).length()
                            < 1e-12 * momentum_before.length().max(1.0),
                        "trial {trial}: momentum {momentum} vs {momentum_before}"
                    );
                }
            }
        }
    }

    #[test]
    fn start_of_step_direction_conserves_angular_momentum_exactly() {
        let n = 30;
        let points: Vec<DVec2> = (0..n)
            .map(|i| DVec2::new(0.2 + 0.02 * i as f64, 0.5))
            .collect();
        let edges = chain_edges(&points, false);
        // A spinning strand: rigid rotation about its middle plus a kick.
        let centre = points[n / 2];
        let mut velocity: Vec<DVec2> = points.iter().map(|&p| 20.0 * (p - centre).perp()).collect();
        velocity[3] += DVec2::new(0.5, 2.0);
        let inverse_mass = vec![1.0; n];
        let angular =
            |v: &[DVec2]| -> f64 { (0..n).map(|i| (points[i] - centre).perp_dot(v[i])).sum() };
        let before = angular(&velocity);
        let dt = 1.0 / 300.0;
        let mut v = velocity.clone();
        project_chain(
            Chain {
                edges: &edges,
                closed: false,
            },
            &points,
            &mut v,
            &inverse_mass,
            dt,
            &settings(ConstraintDirection::StartOfStep),
            &mut ChainScratch::default(),
        );
        assert!((angular(&v) - before).abs() < 1e-12 * before.abs());
        let mut v = velocity;
        project_chain(
            Chain {
                edges: &edges,
                closed: false,
            },
            &points,
            &mut v,
            &inverse_mass,
            dt,
            &settings(ConstraintDirection::EndOfStep),
            &mut ChainScratch::default(),
        );
        // The end-of-step direction loses some: measured, not conserved.
        assert!((angular(&v) - before).abs() > 1e-9 * before.abs());
    }

    #[test]
    fn a_zero_length_edge_is_reported_singular() {
        let points = [DVec2::ZERO, DVec2::ZERO, DVec2::X];
        let edges = [
            IslandEdge {
                a: 0,
                b: 1,
                rest_length: 0.5,
                edge: 0,
            },
            IslandEdge {
                a: 1,
                b: 2,
                rest_length: 1.0,
                edge: 1,
            },
        ];
        let mut v = [DVec2::ZERO; 3];
        let outcome = project_chain(
            Chain {
                edges: &edges,
                closed: false,
            },
            &points,
            &mut v,
            &[1.0; 3],
            0.01,
            &settings(ConstraintDirection::EndOfStep),
            &mut ChainScratch::default(),
        );
        assert!(outcome.singular && !outcome.converged);
        assert!(v.iter().all(|v| v.is_finite()));
    }
}
