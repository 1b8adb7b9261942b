//! Relaxation baselines: Jacobi and Gauss–Seidel projection of one
//! distance constraint at a time, as position-based engines do (zero-compliance XPBD
//! moves the particles exactly as Gauss–Seidel does). Kept so that every figure of the
//! exact solve can be shown beside what most engines do.
//!
//! Each sweep moves the ends of every edge along it, in inverse-mass proportion, to its
//! rest length: Gauss–Seidel one edge after another with the latest corrections,
//! Jacobi all edges from the same corrections, each particle averaging what its edges
//! ask. Sweeps stop at the tolerance or the iteration cap; then `v += Δ / dt`. Like the
//! exact kernel it carries corrections and forms edges from coordinate differences.
//! Works on any island; its edges need no particular order.

use bevy::math::DVec2;

use super::island_edge::IslandEdge;
use super::projection::{Bodies, ProjectionOutcome, ProjectionSettings, ROUND_OFF_FLOOR};

/// How the sweeps use the corrections.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Relaxation {
    /// All edges from the same corrections; each particle takes the mean of its edges'.
    Jacobi,
    /// One edge after another, each seeing the corrections before it.
    GaussSeidel,
}

/// Reusable buffers for [`relax`], indexed by packed particle.
#[derive(Clone, Debug, Default)]
pub struct RelaxationScratch {
    correction: Vec<DVec2>,
    sum: Vec<DVec2>,
    count: Vec<u32>,
    predicted_edge: Vec<DVec2>,
}

impl RelaxationScratch {
    /// Make room for `particles` packed particles and islands of `edges` edges.
    pub fn reserve(&mut self, particles: usize, edges: usize) {
        if self.correction.len() < particles {
            self.correction.resize(particles, DVec2::ZERO);
            self.sum.resize(particles, DVec2::ZERO);
            self.count.resize(particles, 0);
        }
        if self.predicted_edge.len() < edges {
            self.predicted_edge.resize(edges, DVec2::ZERO);
        }
    }
}

/// Relax the velocities of the island of `edges` towards rest lengths at the end of the
/// step. Returns the sweeps done and the residual left (`max |C| / L²`).
pub fn relax(
    edges: &[IslandEdge],
    bodies: Bodies,
    dt: f64,
    method: Relaxation,
    settings: &ProjectionSettings,
    scratch: &mut RelaxationScratch,
) -> ProjectionOutcome {
    let Bodies {
        position,
        velocity,
        inverse_mass: w,
        ..
    } = bodies;
    scratch.reserve(position.len(), edges.len());
    let s = scratch;
    for (k, e) in edges.iter().enumerate() {
        let (a, b) = (e.a as usize, e.b as usize);
        s.predicted_edge[k] = position[b] - position[a] + dt * (velocity[b] - velocity[a]);
        for p in [a, b] {
            s.correction[p] = DVec2::ZERO;
            s.count[p] = 0;
        }
    }
    for e in edges {
        if w[e.a as usize] + w[e.b as usize] > 0.0 {
            s.count[e.a as usize] += 1;
            s.count[e.b as usize] += 1;
        }
    }
    let current = |s: &RelaxationScratch, k: usize, e: &IslandEdge| {
        s.predicted_edge[k] + s.correction[e.b as usize] - s.correction[e.a as usize]
    };
    let mut outcome = ProjectionOutcome::default();
    loop {
        let mut residual = 0.0f64;
        let mut locked = 0;
        for (k, e) in edges.iter().enumerate() {
            let edge = current(s, k, e);
            if w[e.a as usize] + w[e.b as usize] <= 0.0 || edge.length_squared() == 0.0 {
                locked += 1;
                continue;
            }
            let rest_squared = e.rest_length * e.rest_length;
            residual = residual.max((edge.length_squared() - rest_squared).abs() / rest_squared);
        }
        outcome.residual = residual;
        outcome.locked = locked;
        if residual <= settings.tolerance.max(ROUND_OFF_FLOOR) {
            outcome.converged = true;
            break;
        }
        if outcome.iterations >= settings.max_iterations {
            break;
        }
        outcome.iterations += 1;
        // Gauss–Seidel moves the corrections at once; Jacobi gathers the moves (its sums
        // are zero between sweeps) and then averages them per particle.
        for (k, e) in edges.iter().enumerate() {
            let (a, b) = (e.a as usize, e.b as usize);
            if let Some(step) = restoring_step(current(s, k, e), e.rest_length, w[a] + w[b]) {
                let moved = match method {
                    Relaxation::GaussSeidel => &mut s.correction,
                    Relaxation::Jacobi => &mut s.sum,
                };
                moved[a] += w[a] * step;
                moved[b] -= w[b] * step;
            }
        }
        if method == Relaxation::Jacobi {
            for e in edges {
                for p in [e.a as usize, e.b as usize] {
                    if s.count[p] > 0 {
                        s.correction[p] += s.sum[p] / s.count[p] as f64;
                        // Applied once, however many edges meet here.
                        s.sum[p] = DVec2::ZERO;
                    }
                }
            }
        }
    }
    for e in edges {
        for p in [e.a as usize, e.b as usize] {
            if w[p] > 0.0 {
                velocity[p] += s.correction[p] / dt;
            }
            // Applied once, however many edges meet here.
            s.correction[p] = DVec2::ZERO;
        }
    }
    outcome
}

/// The move, per unit inverse mass, that brings `edge` to `rest_length` (applied `+w_a`
/// at its start and `−w_b` at its end), if it has a direction and a free end.
fn restoring_step(edge: DVec2, rest_length: f64, inverse_mass_sum: f64) -> Option<DVec2> {
    let length = edge.length();
    (length > 0.0 && inverse_mass_sum > 0.0)
        .then(|| (length - rest_length) / (length * inverse_mass_sum) * edge)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::projection::ConstraintDirection;

    fn settings(iterations: u32) -> ProjectionSettings {
        ProjectionSettings {
            tolerance: 1e-12,
            max_iterations: iterations,
            direction: ConstraintDirection::EndOfStep,
            max_restep_depth: 0,
        }
    }

    /// A zig-zag strand pulled apart at its ends.
    fn stretched(n: usize) -> (Vec<DVec2>, Vec<DVec2>, Vec<IslandEdge>) {
        let position: Vec<DVec2> = (0..n)
            .map(|i| DVec2::new(0.01 * i as f64, 0.005 * (i % 2) as f64))
            .collect();
        let mut velocity = vec![DVec2::ZERO; n];
        velocity[0] = DVec2::new(-3.0, 0.0);
        velocity[n - 1] = DVec2::new(3.0, 1.0);
        let edges = (0..n - 1)
            .map(|k| IslandEdge {
                a: k as u32,
                b: k as u32 + 1,
                rest_length: position[k].distance(position[k + 1]),
                edge: k as u32,
            })
            .collect();
        (position, velocity, edges)
    }

    fn error(position: &[DVec2], velocity: &[DVec2], edges: &[IslandEdge], dt: f64) -> f64 {
        edges
            .iter()
            .map(|e| {
                let end = |p: u32| position[p as usize] + dt * velocity[p as usize];
                (end(e.b).distance(end(e.a)) - e.rest_length).abs() / e.rest_length
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn more_sweeps_shrink_the_error_and_gauss_seidel_beats_jacobi() {
        let dt = 1.0 / 300.0;
        let (position, initial, edges) = stretched(20);
        let inverse_mass = vec![1.0; 20];
        let mut scratch = RelaxationScratch::default();
        let mut run = |method, sweeps| {
            let mut velocity = initial.clone();
            let bodies = Bodies::new(&position, &mut velocity, &inverse_mass);
            let outcome = relax(&edges, bodies, dt, method, &settings(sweeps), &mut scratch);
            let momentum: DVec2 = velocity.iter().sum();
            (error(&position, &velocity, &edges, dt), outcome, momentum)
        };
        let before = error(&position, &initial, &edges, dt);
        let (gs_1, outcome, momentum) = run(Relaxation::GaussSeidel, 1);
        assert_eq!(outcome.iterations, 1);
        assert!(!outcome.converged);
        // Gauss–Seidel's impulses are equal and opposite: momentum is kept.
        let initial_momentum: DVec2 = initial.iter().sum();
        assert!((momentum - initial_momentum).length() < 1e-12);
        let (gs_10, _, _) = run(Relaxation::GaussSeidel, 10);
        let (jacobi_10, _, _) = run(Relaxation::Jacobi, 10);
        let (gs_many, outcome, _) = run(Relaxation::GaussSeidel, 5000);
        assert!(
            before > gs_1 && gs_1 > gs_10 && gs_10 > gs_many,
            "{before} {gs_1} {gs_10}"
        );
        assert!(
            gs_10 < jacobi_10 && jacobi_10 < before,
            "{gs_10} {jacobi_10}"
        );
        // Relaxation converges, slowly: thousands of sweeps for what one exact solve
        // with a few Newton steps does.
        assert!(
            outcome.converged && gs_many < 1e-11,
            "{outcome:?} {gs_many:e}"
        );
        assert!(outcome.iterations > 50, "{outcome:?}");
    }
}
