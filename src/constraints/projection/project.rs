//! One projection of an island: from the unconstrained end of step, solve the island's
//! system for the edge multipliers and move the correction, until every edge meets the
//! tolerance or the cap is hit.

use bevy::math::DVec2;

use super::edge;
use super::iterate::iterate;
use super::restep::restep;
use super::scratch::IslandScratch;
use super::settings::{ProjectionOutcome, ProjectionSettings};
use super::view::Bodies;
use super::walk::Walk;
use crate::constraints::island_edge::IslandEdge;

/// Project one island (see [`super::project_island`]) walked by `walk`.
pub(super) fn project_walk<W: Walk>(
    edges: &[IslandEdge],
    walk: W,
    bodies: Bodies,
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    let m = edges.len();
    if m == 0 {
        return ProjectionOutcome {
            converged: true,
            ..Default::default()
        };
    }
    let particles = walk.particles(edges);
    scratch.reserve(m, particles);
    let particle = |j: usize| walk.particle(edges, j);

    // Iterate on the correction Δ to the predicted motion, x̃ = x + dt v* + Δ, and on
    // edges formed from differences, so that nothing depends on the distance from the
    // origin and v = v* + Δ / dt changes the momentum only by the impulses.
    let Bodies {
        position,
        velocity,
        inverse_mass,
        end_change,
    } = bodies;
    for j in 0..particles {
        scratch.correction[j] = DVec2::ZERO;
        scratch.inverse_mass[j] = inverse_mass[particle(j)];
    }
    for (k, e) in edges.iter().enumerate() {
        let (a, b) = (e.a as usize, e.b as usize);
        scratch.start_direction[k] = position[b] - position[a];
        scratch.predicted_edge[k] = scratch.start_direction[k] + dt * (velocity[b] - velocity[a]);
        let (ja, jb) = walk.ends(k, particles);
        let w = scratch.inverse_mass[ja] + scratch.inverse_mass[jb];
        scratch.locked[k] = edge::locked(scratch.predicted_edge[k], w);
    }
    let locked = scratch.locked[..m].iter().filter(|&&l| l).count() as u32;
    scratch.edge_impulse[..m].fill(0.0);
    let mut outcome = iterate(edges, walk, settings, scratch);
    if !outcome.converged && settings.max_restep_depth > 0 {
        // Too far for one projection (a fast turn, a heavy end on a light strand):
        // the step again in substeps, each projected from the last one's end.
        let whole = outcome;
        outcome = restep(edges, walk, position, velocity, dt, settings, scratch);
        outcome.iterations += whole.iterations;
    }
    outcome.locked = locked;
    let correction = &scratch.correction[..particles];
    for (j, c) in correction.iter().enumerate() {
        if scratch.inverse_mass[j] > 0.0 {
            velocity[particle(j)] += *c / dt;
        }
    }
    if let (true, Some(end_change)) = (outcome.restepped, end_change) {
        for j in 0..particles {
            if scratch.inverse_mass[j] > 0.0 {
                let p = particle(j);
                end_change[p] = scratch.substep_velocity[j] - velocity[p];
            }
        }
    }
    outcome
}
