//! Fast projection of an island onto its length constraints. A path or a loop has a
//! tridiagonal
//! system (Thomas; Sherman–Morrison for the loop's corners); a tree or a general graph
//! a sparse one, factored by [`crate::linalg::sparse`] in the order its layout planned.
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
//! **Contacts.** The islands that contact rows touch are projected together with
//! those rows by the crate's `contact` module, which walks their edges with this module's
//! `walk`s and factors them with its `scratch`'s factors.
//!
//! A pure kernel: slices in, slices out, no allocation once the scratch is sized. One
//! projection is in `project`, its Newton iterations in `iterate` (shared with each
//! substep of a re-stepped one, `restep`), the assembly and solve of the system in
//! `assembly`.

mod assembly;
pub(crate) mod edge;
mod iterate;
mod project;
mod restep;
pub(crate) mod scratch;
mod settings;
pub(crate) mod view;
pub(crate) mod walk;

pub use scratch::IslandScratch;
pub use settings::{
    ConstraintDirection, MAX_RESTEP_DEPTH, ProjectionOutcome, ProjectionSettings, ROUND_OFF_FLOOR,
};
pub use view::{Bodies, Chain, Graph, IslandView};

use project::project_walk;
use walk::with_walk;

/// Project the velocities of one chain so that every edge ends the step at its rest
/// length; see [`project_island`].
pub fn project_chain(
    chain: Chain,
    bodies: Bodies,
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    project_island(IslandView::Chain(chain), bodies, dt, settings, scratch)
}

/// Project the velocities of one island so that every edge ends the step at its rest
/// length. Only free particles of the island change velocity. Returns how the iteration ended; on a singular system the
/// corrections found so far are applied. Trees and graphs always use the end-of-step
/// direction: their sparse factorization needs the symmetric system.
pub fn project_island(
    island: IslandView,
    bodies: Bodies,
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    with_walk!(island, |edges, walk| {
        project_walk(edges, walk, bodies, dt, settings, scratch)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::graph::GraphLayout;
    use crate::constraints::island_edge::IslandEdge;
    use bevy::math::DVec2;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    fn chain_edges(points: &[DVec2], closed: bool) -> Vec<IslandEdge> {
        IslandEdge::chain(points, closed)
    }

    fn settings(direction: ConstraintDirection) -> ProjectionSettings {
        ProjectionSettings {
            tolerance: 1e-13,
            max_iterations: 50,
            direction,
            max_restep_depth: 0,
        }
    }

    struct Case<'a> {
        edges: &'a [IslandEdge],
        closed: bool,
        position: &'a [DVec2],
        inverse_mass: &'a [f64],
        dt: f64,
    }

    impl Case<'_> {
        fn project(
            &self,
            velocity: &mut [DVec2],
            direction: ConstraintDirection,
        ) -> ProjectionOutcome {
            project_chain(
                Chain {
                    edges: self.edges,
                    closed: self.closed,
                },
                Bodies::new(self.position, velocity, self.inverse_mass),
                self.dt,
                &settings(direction),
                &mut IslandScratch::default(),
            )
        }

        fn max_relative_error(&self, velocity: &[DVec2]) -> f64 {
            self.edges
                .iter()
                .map(|e| {
                    let (a, b) = (e.a as usize, e.b as usize);
                    let end = |i: usize| self.position[i] + self.dt * velocity[i];
                    (end(b).distance(end(a)) - e.rest_length).abs() / e.rest_length
                })
                .fold(0.0, f64::max)
        }
    }

    #[test]
    fn random_chains_end_the_step_at_rest_length() {
        let mut rng = StdRng::seed_from_u64(3);
        for trial in 0..40 {
            let closed = trial % 4 == 3;
            let n = rng.random_range(3..80);
            let points: Vec<DVec2> = if closed {
                // A regular polygon, so the loop closes.
                (0..n)
                    .map(|i| {
                        let angle = std::f64::consts::TAU * i as f64 / n as f64;
                        DVec2::new(0.5, 0.5) + 0.1 * DVec2::from_angle(angle)
                    })
                    .collect()
            } else {
                let mut points = vec![DVec2::new(0.5, 0.5)];
                let mut heading: f64 = 0.0;
                for _ in 1..n {
                    heading += rng.random_range(-0.8..0.8);
                    let step = rng.random_range(0.005..0.03);
                    points.push(*points.last().unwrap() + step * DVec2::from_angle(heading));
                }
                points
            };
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
            let momentum = |v: &[DVec2]| -> DVec2 {
                (0..n)
                    .filter(|&i| inverse_mass[i] > 0.0)
                    .map(|i| v[i] / inverse_mass[i])
                    .sum()
            };
            let case = Case {
                edges: &edges,
                closed,
                position: &points,
                inverse_mass: &inverse_mass,
                dt: 1.0 / 3000.0,
            };
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
                let outcome = case.project(&mut v, direction);
                assert!(
                    outcome.converged,
                    "trial {trial} {direction:?}: {outcome:?}"
                );
                // Up to ~5 % of an edge per step converges fast; the extreme trials move
                // edges by up to 20 % and only need to converge within the default cap.
                let cap = if speed <= 1.0 { 6 } else { 20 };
                assert!(outcome.iterations <= cap, "trial {trial}: {outcome:?}");
                let error = case.max_relative_error(&v);
                assert!(error < 1e-12, "trial {trial} {direction:?}: {error}");
                if inverse_mass[0] > 0.0 {
                    let (after, before) = (momentum(&v), momentum(&velocity));
                    assert!(
                        (after - before).length() < 1e-12 * before.length().max(1.0),
                        "trial {trial}: momentum {after} vs {before}"
                    );
                }
            }
        }
    }

    /// Random points with a random spanning tree, plus `extra` random cross-links.
    fn random_graph(n: usize, extra: usize, rng: &mut StdRng) -> (Vec<DVec2>, Vec<IslandEdge>) {
        let points: Vec<DVec2> = (0..n)
            .map(|_| DVec2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)))
            .collect();
        let mut pairs: Vec<(u32, u32)> = (1..n)
            .map(|i| (rng.random_range(0..i) as u32, i as u32))
            .collect();
        while pairs.len() < n - 1 + extra {
            let (a, b) = (rng.random_range(0..n) as u32, rng.random_range(0..n) as u32);
            if a != b && !pairs.contains(&(a, b)) && !pairs.contains(&(b, a)) {
                pairs.push((a, b));
            }
        }
        let edges = IslandEdge::between(&points, &pairs);
        (points, edges)
    }

    fn project_graph(
        edges: &[IslandEdge],
        layout: &GraphLayout,
        position: &[DVec2],
        velocity: &mut [DVec2],
        inverse_mass: &[f64],
        scratch: &mut IslandScratch,
    ) -> ProjectionOutcome {
        project_island(
            IslandView::Graph(Graph { edges, layout }),
            Bodies::new(position, velocity, inverse_mass),
            1.0 / 3000.0,
            &settings(ConstraintDirection::EndOfStep),
            scratch,
        )
    }

    #[test]
    fn random_trees_and_graphs_end_the_step_at_rest_length() {
        let mut rng = StdRng::seed_from_u64(4);
        for trial in 0..40 {
            let n = rng.random_range(2..60);
            // Trees, then graphs with a few loops (2n − 3 edges at most stay independent).
            let extra = if trial % 2 == 0 {
                0
            } else {
                rng.random_range(1..n.max(2))
            };
            let (points, mut edges) = random_graph(n, extra.min(n.saturating_sub(2)), &mut rng);
            let mut pinned = vec![false; n];
            let mut inverse_mass: Vec<f64> =
                (0..n).map(|_| 1.0 / rng.random_range(0.1..10.0)).collect();
            if trial % 3 == 1 {
                pinned[0] = true;
                inverse_mass[0] = 0.0;
            }
            let layout = GraphLayout::new(&mut edges, &pinned);
            let velocity: Vec<DVec2> = (0..n)
                .map(|i| {
                    let v = DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                    if pinned[i] { DVec2::ZERO } else { 3.0 * v }
                })
                .collect();
            let mut v = velocity.clone();
            let mut scratch = IslandScratch::default();
            let outcome = project_graph(
                &edges,
                &layout,
                &points,
                &mut v,
                &inverse_mass,
                &mut scratch,
            );
            assert!(outcome.converged, "trial {trial}: {outcome:?}");
            // Trees converge as fast as chains; random cross-links can make a graph
            // nearly rigid, and Newton slower, but within the default cap.
            let cap = if extra == 0 { 6 } else { 20 };
            assert!(outcome.iterations <= cap, "trial {trial}: {outcome:?}");
            let case = Case {
                edges: &edges,
                closed: false,
                position: &points,
                inverse_mass: &inverse_mass,
                dt: 1.0 / 3000.0,
            };
            let error = case.max_relative_error(&v);
            assert!(error < 1e-12, "trial {trial}: {error:e}");
            if !pinned[0] {
                let momentum =
                    |v: &[DVec2]| -> DVec2 { (0..n).map(|i| v[i] / inverse_mass[i]).sum() };
                let (after, before) = (momentum(&v), momentum(&velocity));
                assert!(
                    (after - before).length() < 1e-12 * before.length().max(1.0),
                    "trial {trial}: momentum {after} vs {before}"
                );
            }
        }
    }

    #[test]
    fn a_redundant_constraint_is_dropped_and_the_rest_met() {
        // A wheel: a square, its centre and four spokes. Five particles keep seven
        // distances independent in 2D; the eighth follows from them.
        let points = [
            DVec2::new(0.0, 0.0),
            DVec2::new(0.1, 0.0),
            DVec2::new(0.1, 0.1),
            DVec2::new(0.0, 0.1),
            DVec2::new(0.05, 0.05),
        ];
        let spokes = [
            (0, 1),
            (1, 2),
            (2, 3),
            (3, 0),
            (0, 4),
            (1, 4),
            (2, 4),
            (3, 4),
        ];
        let mut edges = IslandEdge::between(&points, &spokes);
        let layout = GraphLayout::new(&mut edges, &[false; 5]);
        // Spinning, and one corner kicked outwards.
        let centre = points[4];
        let mut velocity: Vec<DVec2> = points.iter().map(|&p| 30.0 * (p - centre).perp()).collect();
        velocity[2] += DVec2::new(2.0, 1.0);
        let mut scratch = IslandScratch::default();
        let outcome = project_graph(
            &edges,
            &layout,
            &points,
            &mut velocity,
            &[1.0; 5],
            &mut scratch,
        );
        assert!(outcome.converged && !outcome.singular, "{outcome:?}");
        assert!(scratch.factors.sparse.dropped >= 1);
        let case = Case {
            edges: &edges,
            closed: false,
            position: &points,
            inverse_mass: &[1.0; 5],
            dt: 1.0 / 3000.0,
        };
        assert!(case.max_relative_error(&velocity) < 1e-12);
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
        let case = Case {
            edges: &edges,
            closed: false,
            position: &points,
            inverse_mass: &inverse_mass,
            dt: 1.0 / 300.0,
        };
        let mut v = velocity.clone();
        case.project(&mut v, ConstraintDirection::StartOfStep);
        assert!((angular(&v) - before).abs() < 1e-12 * before.abs());
        let mut v = velocity;
        case.project(&mut v, ConstraintDirection::EndOfStep);
        // The end-of-step direction loses some: measured, not conserved.
        assert!((angular(&v) - before).abs() > 1e-9 * before.abs());
    }

    #[test]
    fn a_zero_length_edge_is_locked_and_the_rest_solved() {
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
        let case = Case {
            edges: &edges,
            closed: false,
            position: &points,
            inverse_mass: &[1.0; 3],
            dt: 0.01,
        };
        let mut v = [DVec2::ZERO, DVec2::ZERO, DVec2::new(3.0, 1.0)];
        let outcome = case.project(&mut v, ConstraintDirection::EndOfStep);
        assert_eq!(outcome.locked, 1);
        assert!(outcome.converged && !outcome.singular);
        assert!(v.iter().all(|v| v.is_finite()));
        let length = (points[2] + 0.01 * v[2]).distance(points[1] + 0.01 * v[1]);
        assert!((length - 1.0).abs() < 1e-12);
    }
}
