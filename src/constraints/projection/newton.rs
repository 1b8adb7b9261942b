//! The projection's Newton loop: from the unconstrained end of step, solve the island's
//! system for the edge multipliers (and, with contacts, the contact impulses), move the
//! correction, until every edge meets the tolerance or the cap is hit.

use bevy::math::DVec2;

use super::ContactRow;
use super::contact_rows::{POLISH_RESIDUAL, contact_violation, localize_contacts};
use super::elimination::eliminate_contacts;
use super::scratch::IslandScratch;
use super::settings::{
    ConstraintDirection, ProjectionOutcome, ProjectionSettings, ROUND_OFF_FLOOR,
};
use super::view::Bodies;
use super::walk::Walk;
use crate::constraints::island_edge::IslandEdge;
use crate::constraints::tridiagonal::SingularPivot;

/// Project one island (see [`super::project_island`]) walked by `walk`.
pub(super) fn project_walk<W: Walk>(
    edges: &[IslandEdge],
    walk: W,
    bodies: Bodies,
    contacts: &[ContactRow],
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
    let shortest = edges
        .iter()
        .map(|e| e.rest_length)
        .fold(f64::INFINITY, f64::min);

    // Iterate on the correction Δ to the predicted motion, x̃ = x + dt v* + Δ, and on
    // edges formed from differences, so that nothing depends on the distance from the
    // origin and v = v* + Δ / dt changes the momentum only by the impulses.
    let Bodies {
        position,
        velocity,
        inverse_mass,
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
        scratch.locked[k] =
            e.edge == IslandEdge::GAP || scratch.predicted_edge[k].length_squared() * w <= 0.0;
    }
    if !contacts.is_empty() {
        scratch.reserve_contacts(m, walk.max_degree(), velocity.len());
    }
    let locked = (scratch.locked[..m].iter().zip(edges))
        .filter(|&(&l, e)| l && e.edge != IslandEdge::GAP)
        .count() as u32;
    // Contacts solved exactly first; if that asks for an absurd correction, once more
    // with the iterative contact solve, whose truncation damps nearly dependent rows.
    let mut outcome = ProjectionOutcome::default();
    for exact in [true, false] {
        if !exact && (contacts.is_empty() || !outcome.rejected) {
            break;
        }
        scratch.correction[..particles].fill(DVec2::ZERO);
        scratch.edge_impulse[..m].fill(0.0);
        scratch.exact_contacts = exact;
        localize_contacts(contacts, particles, &particle, velocity, dt, scratch);
        outcome = iterate(edges, walk, shortest, settings, scratch);
        outcome.locked = locked;
        let correction = &scratch.correction[..particles];
        let limit = settings.max_correction * shortest;
        outcome.rejected = settings.max_correction.is_finite()
            && correction
                .iter()
                .any(|c| c.length().is_nan() || c.length() > limit);
    }
    if outcome.rejected {
        outcome.converged = false;
        scratch.edge_impulse[..m].fill(0.0);
        return outcome;
    }
    let correction = &scratch.correction[..particles];
    for (j, c) in correction.iter().enumerate() {
        if scratch.inverse_mass[j] > 0.0 {
            velocity[particle(j)] += *c / dt;
        }
    }
    outcome
}

/// The Newton iterations from the correction in `scratch` (zero) with its localized
/// contact rows, until the edges meet the tolerance and the contacts are settled.
fn iterate<W: Walk>(
    edges: &[IslandEdge],
    walk: W,
    shortest: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    let m = edges.len();
    let particles = walk.particles(edges);
    let direction = if scratch.rows.is_empty() && !walk.symmetric_only() {
        settings.direction
    } else {
        ConstraintDirection::EndOfStep
    };
    let mut outcome = ProjectionOutcome::default();
    let contact_tolerance = settings.contact_tolerance;
    let mut previous_violation = f64::INFINITY;
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
        let violation = contact_violation(&s.rows, &s.correction);
        outcome.residual = residual;
        outcome.contact_violation = violation;
        // The contacts are met to their tolerance, or as well as the complementarity
        // solve manages once that stops improving; then they are settled, and the last
        // iterations polish the edges alone, converging quadratically (an inexact
        // contact solve would otherwise leave its noise, squared, in the edges).
        let nearly = residual <= POLISH_RESIDUAL;
        let settled = violation <= contact_tolerance || violation > 0.5 * previous_violation;
        if !s.rows.is_empty() && nearly && settled {
            s.rows.clear();
        }
        previous_violation = violation;
        let edges_done = residual <= settings.tolerance.max(ROUND_OFF_FLOOR);
        if edges_done && s.rows.is_empty() {
            outcome.converged = true;
            break;
        }
        if outcome.iterations >= settings.max_iterations {
            outcome.converged = false;
            break;
        }
        outcome.iterations += 1;
        // Pivoting that has not settled in half the iterations is on a problem whose
        // linearization keeps moving: the iterative solve's damping finishes it.
        if s.exact_contacts && 2 * outcome.iterations > settings.max_iterations {
            s.exact_contacts = false;
        }
        let trust = if s.exact_contacts {
            0.5 * shortest
        } else {
            f64::INFINITY
        };
        if newton_step(m, particles, walk, direction, contact_tolerance, trust, s).is_err() {
            outcome.singular = true;
            break;
        }
    }

    outcome
}

/// One Newton step on the edges (and contact rows) from the current corrections. With
/// contact rows the step moves no particle by more than `trust`: the linearized edges
/// allow any motion along themselves, and contacts met exactly on that linearization
/// can ask for a lever's swing the edges cannot follow; a shorter step re-linearizes.
fn newton_step<W: Walk>(
    m: usize,
    particles: usize,
    walk: W,
    direction_kind: ConstraintDirection,
    contact_tolerance: f64,
    trust: f64,
    s: &mut IslandScratch,
) -> Result<(), SingularPivot> {
    let rows = s.rows.len();
    for k in 0..m {
        s.rhs[k] = if s.locked[k] { 0.0 } else { -s.constraint[k] };
    }
    walk.solve(m, direction_kind, rows > 0, s)?;

    if rows > 0 {
        eliminate_contacts(m, walk, contact_tolerance, s);
        s.step_start[..particles].copy_from_slice(&s.correction[..particles]);
    }

    let direction: &[DVec2] = match direction_kind {
        ConstraintDirection::EndOfStep => &s.edge[..m],
        ConstraintDirection::StartOfStep => &s.start_direction[..m],
    };
    for (k, d) in direction.iter().enumerate() {
        let impulse = 2.0 * s.rhs[k] * *d;
        s.step_impulse[k] = -2.0 * s.rhs[k] * d.length();
        let (a, b) = walk.ends(k, particles);
        s.correction[a] -= s.inverse_mass[a] * impulse;
        s.correction[b] += s.inverse_mass[b] * impulse;
    }
    for c in 0..rows {
        let (row, mu) = (s.rows[c], s.impulse[c]);
        for &(j, coefficient) in &row.entries[..row.count] {
            s.correction[j as usize] += s.inverse_mass[j as usize] * coefficient * mu * row.normal;
        }
    }
    let mut shrink = 1.0;
    if rows > 0 {
        let (start, correction) = (&s.step_start[..particles], &mut s.correction[..particles]);
        let longest = start
            .iter()
            .zip(correction.iter())
            .map(|(a, b)| (*b - *a).length())
            .fold(0.0f64, f64::max);
        if longest > trust {
            shrink = trust / longest;
            for (a, b) in start.iter().zip(correction.iter_mut()) {
                *b = *a + shrink * (*b - *a);
            }
        }
    }
    for k in 0..m {
        s.edge_impulse[k] += shrink * s.step_impulse[k];
    }
    Ok(())
}
