//! The projection's Newton loop: from the unconstrained end of step, solve the island's
//! system for the edge multipliers and move the correction, until every edge meets the
//! tolerance or the cap is hit.

use bevy::math::DVec2;

use super::restep::restep;
use super::scratch::IslandScratch;
use super::settings::{
    ConstraintDirection, ProjectionOutcome, ProjectionSettings, ROUND_OFF_FLOOR,
};
use super::view::Bodies;
use super::walk::Walk;
use crate::constraints::island_edge::IslandEdge;
use crate::constraints::tridiagonal::SingularPivot;

/// Past the iteration cap a projection goes on while every `STEADY_WINDOW` Newton
/// steps cut the residual by at least `STEADY_RATE` ...
const STEADY_WINDOW: u32 = 5;
const STEADY_RATE: f64 = 0.5;
/// ... up to this many times the cap.
const STEADY_EXTENSION: u32 = 8;

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
        scratch.locked[k] = scratch.predicted_edge[k].length_squared() * w <= 0.0;
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

/// The Newton iterations from the correction in `scratch` (zero), until the edges meet
/// the tolerance.
pub(super) fn iterate<W: Walk>(
    edges: &[IslandEdge],
    walk: W,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    let m = edges.len();
    let particles = walk.particles(edges);
    let direction = if walk.symmetric_only() {
        ConstraintDirection::EndOfStep
    } else {
        settings.direction
    };
    let mut outcome = ProjectionOutcome::default();
    let mut checkpoint = f64::INFINITY;
    loop {
        let s = &mut *scratch;
        let mut residual = 0.0f64;
        for (k, e) in edges.iter().enumerate() {
            let (a, b) = walk.ends(k, particles);
            s.edge[k] = s.predicted_edge[k] + (s.correction[b] - s.correction[a]);
            let rest_squared = e.rest_length * e.rest_length;
            s.constraint[k] = s.edge[k].length_squared() - rest_squared;
            if !s.locked[k] {
                residual = residual.max(s.constraint[k].abs() / rest_squared);
            }
        }
        outcome.residual = residual;
        if residual <= settings.tolerance.max(ROUND_OFF_FLOOR) {
            outcome.converged = true;
            break;
        }
        // Past the cap, only while the residual still falls steadily: heavy particles
        // on light ones converge linearly (and not monotonically), but get there.
        if outcome.iterations >= settings.max_iterations {
            let past = outcome.iterations - settings.max_iterations;
            if past.is_multiple_of(STEADY_WINDOW) {
                if residual > STEADY_RATE * checkpoint
                    || outcome.iterations >= settings.max_iterations * STEADY_EXTENSION
                {
                    break;
                }
                checkpoint = residual;
            }
        }
        outcome.iterations += 1;
        if newton_step(m, particles, walk, direction, s).is_err() {
            outcome.singular = true;
            break;
        }
    }
    outcome
}

/// One Newton step on the edges from the current corrections.
fn newton_step<W: Walk>(
    m: usize,
    particles: usize,
    walk: W,
    direction_kind: ConstraintDirection,
    s: &mut IslandScratch,
) -> Result<(), SingularPivot> {
    for k in 0..m {
        s.rhs[k] = if s.locked[k] { 0.0 } else { -s.constraint[k] };
    }
    walk.solve(m, direction_kind, false, s)?;
    let direction: &[DVec2] = match direction_kind {
        ConstraintDirection::EndOfStep => &s.edge[..m],
        ConstraintDirection::StartOfStep => &s.start_direction[..m],
    };
    for (k, d) in direction.iter().enumerate() {
        let impulse = 2.0 * s.rhs[k] * *d;
        s.edge_impulse[k] -= 2.0 * s.rhs[k] * d.length();
        let (a, b) = walk.ends(k, particles);
        s.correction[a] -= s.inverse_mass[a] * impulse;
        s.correction[b] += s.inverse_mass[b] * impulse;
    }
    Ok(())
}
