//! Re-stepping an island whose projection did not converge in one: the step's motion
//! taken again in substeps, each projected from where the last one ended.
//!
//! One projection from `x + dt v*` fails when the predicted end is too far from the
//! constraint manifold for Newton's linearization: an edge turning through a large
//! angle in the step, or a heavy particle on a light strand, whose light particles the
//! mass-weighted step would fling sideways to keep the heavy one on its line. A
//! substep of `h` brings the predicted end `h²` closer, so halving it enough always
//! converges. The substeps are SHAKE's: each keeps its own velocity `u` (starting at
//! `v*`, changed by its projection's impulses), each ends exact; the step's velocity
//! is then the chord `(y_n − x) / dt`, so that the rest of the step (contacts,
//! continuous detection, `x += dt v`) sees the straight motion to the exact end.
//! Sizes adapt: a substep that fails is halved, one that converges lets the next
//! double (on the binary grid of the step, so every substep ends on it exactly).

use bevy::math::DVec2;

use super::edge;
use super::iterate::iterate;
use super::scratch::IslandScratch;
use super::settings::{
    ConstraintDirection, MAX_RESTEP_DEPTH, ProjectionOutcome, ProjectionSettings,
};
use super::walk::Walk;
use crate::constraints::island_edge::IslandEdge;
use crate::linalg::SingularPivot;

/// How many times the iteration cap the finest substeps may take.
const DEEPEST_BUDGET: u32 = 16;

/// Re-step the island of `edges` over `dt` (its particles at `position` with the
/// predicted velocities `velocity`, read only). On return `scratch.correction` holds
/// each particle's correction to `x + dt v*`, as a single projection leaves it, and
/// `scratch.edge_impulse` each edge's impulse scaled to the step (tension × dt²). The
/// outcome counts the substeps and every Newton step taken; if a substep of
/// `dt / 2^max_restep_depth` still fails, the rest of the step is taken in one and the
/// outcome is not converged.
pub(super) fn restep<W: Walk>(
    edges: &[IslandEdge],
    walk: W,
    position: &[DVec2],
    velocity: &[DVec2],
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    let m = edges.len();
    let particles = walk.particles(edges);
    scratch.reserve_substeps(m, particles);
    for j in 0..particles {
        scratch.substep_offset[j] = DVec2::ZERO;
        scratch.substep_velocity[j] = velocity[walk.particle(edges, j)];
    }
    scratch.substep_impulse[..m].fill(0.0);
    // A singular system leaves the velocities as they came: the substeps still try.
    let _ = filter_velocities(edges, walk, position, dt, scratch);

    // Time on the grid of the deepest substep: the step is `1 << depth` units.
    let depth = settings.max_restep_depth.min(MAX_RESTEP_DEPTH);
    let total: u64 = 1 << depth;
    let (mut t, mut level) = (0u64, 1u32);
    let mut outcome = ProjectionOutcome::default();
    loop {
        let units = (total >> level).min(total - t);
        let h = dt * units as f64 / total as f64;
        // The finest substep gets a longer budget: halving no longer helps there,
        // and a heavy particle's slow convergence is still convergence.
        let budget = ProjectionSettings {
            max_iterations: settings.max_iterations
                * if level >= depth { DEEPEST_BUDGET } else { 1 },
            ..*settings
        };
        let attempt = substep(edges, walk, position, h, &budget, scratch);
        outcome.iterations += attempt.iterations;
        outcome.residual = attempt.residual;
        outcome.singular |= attempt.singular;
        if !attempt.converged && level < depth {
            level += 1;
            continue;
        }
        commit(m, particles, h, dt, scratch);
        outcome.substeps += 1;
        t += units;
        if !attempt.converged {
            // Out of depth: the rest of the step in one, as far as it goes.
            if t < total {
                let h = dt * (total - t) as f64 / total as f64;
                let rest = substep(edges, walk, position, h, settings, scratch);
                outcome.iterations += rest.iterations;
                outcome.residual = rest.residual;
                outcome.singular |= rest.singular;
                commit(m, particles, h, dt, scratch);
                outcome.substeps += 1;
            }
            break;
        }
        if t == total {
            outcome.converged = true;
            break;
        }
        // Grow again where the grid allows: the hard part may have passed.
        if level > 1 && t.is_multiple_of(total >> (level - 1)) {
            level -= 1;
        }
    }
    // The step's motion as one correction to the prediction: x + dt v* + Δ = y_n.
    for j in 0..particles {
        scratch.correction[j] = scratch.substep_offset[j] - dt * velocity[walk.particle(edges, j)];
    }
    scratch.edge_impulse[..m].copy_from_slice(&scratch.substep_impulse[..m]);
    outcome.restepped = true;
    outcome
}

/// Take out of the substep velocities what would change an edge's length at the start
/// of the step (`J u = 0`, one solve of the island's system, impulses along the
/// edges). What the predictor added unevenly (gravity on a strand whose end is pinned)
/// stretches an edge in proportion to the substep, and bends the strand at its end in
/// the same proportion: on a light strand under a heavy particle the projection would
/// then move the light particles sideways as far whatever the substep. Velocities that
/// keep the lengths leave only the curvature of the motion, which shrinks with it.
fn filter_velocities<W: Walk>(
    edges: &[IslandEdge],
    walk: W,
    position: &[DVec2],
    dt: f64,
    scratch: &mut IslandScratch,
) -> Result<(), SingularPivot> {
    let m = edges.len();
    let particles = walk.particles(edges);
    let s = &mut *scratch;
    for (k, e) in edges.iter().enumerate() {
        let (ja, jb) = walk.ends(k, particles);
        let edge = position[e.b as usize] - position[e.a as usize];
        s.edge[k] = edge;
        s.start_direction[k] = edge;
        s.locked[k] = edge::locked(edge, s.inverse_mass[ja] + s.inverse_mass[jb]);
        s.rhs[k] = if s.locked[k] {
            0.0
        } else {
            -2.0 * edge.dot(s.substep_velocity[jb] - s.substep_velocity[ja])
        };
    }
    walk.solve(m, ConstraintDirection::EndOfStep, false, s)?;
    for k in 0..m {
        let impulse = 2.0 * s.rhs[k] * s.edge[k];
        let ends = walk.ends(k, particles);
        edge::apply(&mut s.substep_velocity, &s.inverse_mass, ends, impulse);
        s.substep_impulse[k] -= 2.0 * s.rhs[k] * s.edge[k].length() * dt;
    }
    Ok(())
}

/// Project one substep of `h` from the substep state in `scratch`; the correction is
/// left in `scratch.correction`, the state unchanged.
fn substep<W: Walk>(
    edges: &[IslandEdge],
    walk: W,
    position: &[DVec2],
    h: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    let m = edges.len();
    let particles = walk.particles(edges);
    let s = &mut *scratch;
    s.correction[..particles].fill(DVec2::ZERO);
    for (k, e) in edges.iter().enumerate() {
        let (ja, jb) = walk.ends(k, particles);
        let start = (position[e.b as usize] - position[e.a as usize])
            + (s.substep_offset[jb] - s.substep_offset[ja]);
        s.start_direction[k] = start;
        s.predicted_edge[k] = start + h * (s.substep_velocity[jb] - s.substep_velocity[ja]);
        let w = s.inverse_mass[ja] + s.inverse_mass[jb];
        s.locked[k] = edge::locked(s.predicted_edge[k], w);
    }
    s.edge_impulse[..m].fill(0.0);
    iterate(edges, walk, settings, s)
}

/// Move the substep state by the substep of `h` just projected, and add its impulses,
/// scaled to the step of `dt` (an impulse over `h` is a tension × h²).
fn commit(m: usize, particles: usize, h: f64, dt: f64, s: &mut IslandScratch) {
    for j in 0..particles {
        let c = s.correction[j];
        s.substep_offset[j] += h * s.substep_velocity[j] + c;
        if s.inverse_mass[j] > 0.0 {
            s.substep_velocity[j] += c / h;
        }
    }
    let scale = dt / h;
    for k in 0..m {
        s.substep_impulse[k] += s.edge_impulse[k] * scale;
    }
}

#[cfg(test)]
mod tests {
    use super::super::view::{Bodies, Chain, Graph, IslandView};
    use super::super::{IslandScratch, project_island};
    use super::*;
    use crate::constraints::graph::GraphLayout;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    fn settings(max_restep_depth: u32) -> ProjectionSettings {
        ProjectionSettings {
            tolerance: 1e-12,
            max_iterations: 20,
            direction: ConstraintDirection::EndOfStep,
            max_restep_depth,
        }
    }

    /// A rope of `n` particles from the origin, bent a little at random, its last
    /// particle `ratio` times heavier; turning about the origin at `omega`, with one
    /// step of gravity added.
    fn swinging_rope(
        n: usize,
        ratio: f64,
        omega: f64,
        dt: f64,
        seed: u64,
    ) -> (Vec<DVec2>, Vec<DVec2>, Vec<f64>) {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut points = vec![DVec2::ZERO];
        let mut heading = -1.2f64;
        for _ in 1..n {
            heading += rng.random_range(-0.05..0.05);
            points.push(*points.last().unwrap() + 0.02 * DVec2::from_angle(heading));
        }
        let gravity = DVec2::new(0.0, -9.81);
        let velocity = points
            .iter()
            .map(|&p| omega * p.perp() + dt * gravity)
            .collect();
        let mut inverse_mass = vec![1.0; n];
        inverse_mass[n - 1] = 1.0 / ratio;
        (points, velocity, inverse_mass)
    }

    fn max_error(edges: &[IslandEdge], position: &[DVec2], velocity: &[DVec2], dt: f64) -> f64 {
        let end = |i: u32| position[i as usize] + dt * velocity[i as usize];
        edges
            .iter()
            .map(|e| (end(e.b).distance(end(e.a)) - e.rest_length).abs() / e.rest_length)
            .fold(0.0, f64::max)
    }

    #[test]
    fn a_heavy_pendulum_at_a_game_step_ends_exact_when_re_stepped() {
        let dt = 1.0 / 60.0;
        for (seed, ratio) in [(1, 1e4), (2, 1e6), (3, 1e6)] {
            let (position, velocity, mut inverse_mass) = swinging_rope(21, ratio, 8.0, dt, seed);
            inverse_mass[0] = 0.0;
            let mut start = velocity.clone();
            start[0] = DVec2::ZERO;
            let edges = IslandEdge::chain(&position, false);
            let view = IslandView::Chain(Chain {
                edges: &edges,
                closed: false,
            });
            let mut scratch = IslandScratch::default();
            // One projection cannot: the light rope would have to swing far sideways.
            let mut v = start.clone();
            let once = project_island(
                view,
                Bodies::new(&position, &mut v, &inverse_mass),
                dt,
                &settings(0),
                &mut scratch,
            );
            assert!(!once.converged && !once.restepped, "{seed}: {once:?}");

            let mut v = start.clone();
            let mut end_change = vec![DVec2::ZERO; position.len()];
            let outcome = project_island(
                view,
                Bodies::new(&position, &mut v, &inverse_mass).with_end_change(&mut end_change),
                dt,
                &settings(12),
                &mut scratch,
            );
            assert!(
                outcome.converged && outcome.restepped,
                "{seed}: {outcome:?}"
            );
            assert!(outcome.substeps >= 2, "{seed}: {outcome:?}");
            let error = max_error(&edges, &position, &v, dt);
            assert!(error < 1e-12, "{seed}: {error:e}");
            // The bob leaves along its circle: its end velocity is perpendicular to the
            // rope's chord from the pin, to the rope's own small bend.
            let bob = position.len() - 1;
            let at_end = position[bob] + dt * v[bob];
            let leaving = v[bob] + end_change[bob];
            let radial = leaving.dot(at_end.normalize()) / leaving.length();
            assert!(radial.abs() < 0.05, "{seed}: radial share {radial}");
            assert_eq!(v[0], DVec2::ZERO);
            assert_eq!(end_change[0], DVec2::ZERO);
        }
    }

    #[test]
    fn a_re_stepped_free_strand_keeps_its_momentum() {
        let dt = 1.0 / 60.0;
        let (position, velocity, inverse_mass) = swinging_rope(31, 1e5, 40.0, dt, 7);
        let momentum =
            |v: &[DVec2]| -> DVec2 { v.iter().zip(&inverse_mass).map(|(v, w)| *v / *w).sum() };
        let edges = IslandEdge::chain(&position, false);
        let mut v = velocity.clone();
        let mut end_change = vec![DVec2::ZERO; position.len()];
        let outcome = project_island(
            IslandView::Chain(Chain {
                edges: &edges,
                closed: false,
            }),
            Bodies::new(&position, &mut v, &inverse_mass).with_end_change(&mut end_change),
            dt,
            // A tight cap, so that the fast turn is re-stepped.
            &ProjectionSettings {
                max_iterations: 4,
                ..settings(12)
            },
            &mut IslandScratch::default(),
        );
        assert!(outcome.converged && outcome.restepped, "{outcome:?}");
        assert!(max_error(&edges, &position, &v, dt) < 1e-12);
        let before = momentum(&velocity);
        let scale = before.length().max(1e-3 / inverse_mass[30]);
        // Every substep's impulses are equal and opposite: the chord and the end
        // velocities carry the momentum the strand came in with.
        assert!((momentum(&v) - before).length() < 1e-11 * scale);
        let leaving: Vec<DVec2> = v.iter().zip(&end_change).map(|(v, c)| *v + *c).collect();
        assert!((momentum(&leaving) - before).length() < 1e-11 * scale);
    }

    #[test]
    fn a_heavy_tree_is_re_stepped_through_its_sparse_factor() {
        // Two ropes from one pin, joined at a heavy bob: a graph island.
        let dt = 1.0 / 60.0;
        let (mut position, velocity, _) = swinging_rope(12, 1.0, 8.0, dt, 11);
        let n = position.len();
        let bob = position[n - 1];
        // A second rope from the pin to the bob, bent the other way.
        let mut other = vec![];
        for i in 1..n - 1 {
            let t = i as f64 / (n - 1) as f64;
            other.push(bob * t + 0.03 * (t * std::f64::consts::PI).sin() * bob.perp().normalize());
        }
        position.extend(other.iter().copied());
        let omega = 8.0;
        let velocity: Vec<DVec2> = (0..position.len())
            .map(|i| {
                if i == 0 {
                    DVec2::ZERO
                } else if i < n {
                    velocity[i]
                } else {
                    omega * position[i].perp() + dt * DVec2::new(0.0, -9.81)
                }
            })
            .collect();
        let mut pairs: Vec<(u32, u32)> = (1..n as u32).map(|i| (i - 1, i)).collect();
        let mut previous = 0u32;
        for i in n..position.len() {
            pairs.push((previous, i as u32));
            previous = i as u32;
        }
        pairs.push((previous, n as u32 - 1));
        let mut edges = IslandEdge::between(&position, &pairs);
        let mut inverse_mass = vec![1.0; position.len()];
        inverse_mass[0] = 0.0;
        inverse_mass[n - 1] = 1e-6;
        let mut pinned = vec![false; position.len()];
        pinned[0] = true;
        let layout = GraphLayout::new(&mut edges, &pinned);
        let view = IslandView::Graph(Graph {
            edges: &edges,
            layout: &layout,
        });
        let mut v = velocity.clone();
        let outcome = project_island(
            view,
            Bodies::new(&position, &mut v, &inverse_mass),
            dt,
            &settings(12),
            &mut IslandScratch::default(),
        );
        assert!(outcome.converged && outcome.restepped, "{outcome:?}");
        assert!(max_error(&edges, &position, &v, dt) < 1e-12);
    }
}
