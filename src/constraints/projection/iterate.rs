//! The Newton iterations of a projection: from the correction in the scratch, solve
//! the island's system for the edge multipliers and move the correction, until every
//! edge meets the tolerance or the cap is hit. Shared by one projection (`project`) and
//! each substep of a re-stepped one (`restep`).

use bevy::math::DVec2;

use super::edge;
use super::scratch::IslandScratch;
use super::settings::{
    ConstraintDirection, ProjectionOutcome, ProjectionSettings, ROUND_OFF_FLOOR,
};
use super::walk::Walk;
use crate::constraints::island_edge::IslandEdge;
use crate::linalg::SingularPivot;

/// Past the iteration cap a projection goes on while every `STEADY_WINDOW` Newton
/// steps cut the residual by at least `STEADY_RATE` ...
const STEADY_WINDOW: u32 = 5;
const STEADY_RATE: f64 = 0.5;
/// ... up to this many times the cap.
const STEADY_EXTENSION: u32 = 8;

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
            let rest_squared = e.rest_length * e.rest_length;
            (s.edge[k], s.constraint[k]) = edge::at(
                s.predicted_edge[k],
                s.correction[a],
                s.correction[b],
                rest_squared,
            );
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
        edge::apply(
            &mut s.correction,
            &s.inverse_mass,
            walk.ends(k, particles),
            impulse,
        );
    }
    Ok(())
}
