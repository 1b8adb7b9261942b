//! The contact projection: every island that a set of contact rows touches, projected
//! together with those rows, both sides of every contact moving.
//!
//! The unknowns are the corrections Δ to the predicted end of step of the particles of
//! the touched islands (and of loose free particles the rows touch). Each Newton step
//! linearizes every island's edges at the current iterate and factors its own system
//! `A = J W Jᵀ` (Thomas, Sherman–Morrison or sparse LDLᵀ, as the island's kind asks).
//! The edges then hold, to first order, for any contact impulse: an impulse `f` on an
//! island moves it by its *response* `r = W f − W Jᵀ A⁻¹ J W f`, the motion the
//! island's linearized edges allow. The contact rows (normal and friction) are solved
//! in contact space by projected Gauss–Seidel over those responses, so a contact
//! between two strands pushes both, equal and opposite, each as a whole strand. The
//! impulses are totals over the Newton steps, warm-started from the caller (the
//! previous step's): a contact pushed too hard can let go.
//!
//! The contact rows are met to a tolerance, not to round-off: they keep pairs a
//! cushion apart, and the collision stage verifies what they leave. The edges are met
//! to round-off: once they are nearly met the rows are frozen and the last Newton
//! steps polish the edges alone, converging quadratically.
//!
//! A response is kept twice (`sweeps`): per particle, which the sweeps add to the
//! corrections when a row's impulse changes, and per edge (`A⁻¹ J W f`), summed once
//! per Newton step into the edges' contact multipliers. The state both work on is in
//! `scratch`.

use bevy::math::DVec2;

use super::rows::{ContactRow, RowImpulse};
use super::scratch::{
    ContactScratch, LOOSE, NOT_LOCAL, Part, longest_swing, measure_edges, within_trust,
};
use super::settings::{ContactOutcome, ContactSettings, ContactSolver, Resting};
use super::split::Members;
use super::sweeps::{Sweeps, localize_rows};
use crate::constraints::island_edge::IslandEdge;
use crate::constraints::islands::IslandSet;
use crate::constraints::projection::edge;
use crate::constraints::projection::scratch::Factors;
use crate::constraints::projection::view::{Bodies, IslandView};
use crate::constraints::projection::walk::{Walk, with_walk};
use crate::constraints::projection::{ConstraintDirection, ROUND_OFF_FLOOR};

/// Edge residual (`|C| / L²`) below which the rows may be frozen and the edges
/// polished alone (if what the rows fall short allows no less): the polish then moves
/// particles by at most a few ten-thousandths of an edge. Lower, rows that have
/// stalled keep the Newton steps going while their sweeps stir the edges back above
/// it (the fur held at 2e-4 for ten Newton steps of 16 sweeps each).
const EDGE_POLISH: f64 = 1e-3;

/// Project `islands` and the `loose` free particles together with `rows`: every edge of
/// every island ends the step at its rest length, and every row is met to the contact
/// tolerance (normal rows never pulling, friction within the cone), both sides of each
/// row moving. `impulses[c]` is row c's warm start on entry and its total impulse on
/// return. Only free particles of the parts change velocity. Rows whose particles are
/// all outside the parts are ignored.
#[allow(clippy::too_many_arguments)]
pub fn project_with_contacts(
    set: &IslandSet,
    islands: &[u32],
    loose: &[u32],
    bodies: Bodies,
    rows: &[ContactRow],
    impulses: &mut [RowImpulse],
    dt: f64,
    settings: &ContactSettings,
    scratch: &mut ContactScratch,
) -> ContactOutcome {
    let Bodies {
        position,
        velocity,
        inverse_mass,
        ..
    } = bodies;
    let members = Members {
        set,
        islands,
        loose,
    };
    (scratch.cut).cut(members, position, inverse_mass, rows, impulses);
    // The iteration's start: the parts laid out, the rows localized and warm-started.
    let start = |scratch: &mut ContactScratch| {
        lay_out(
            set,
            islands,
            loose,
            position,
            velocity,
            inverse_mass,
            dt,
            scratch,
        );
        localize_rows(rows, impulses, velocity, dt, scratch);
    };
    start(scratch);
    // A group at rest is met closely by the sweeps (the contact Newton meets its rows
    // to their fixed point whatever the tolerance).
    let resting = match settings.resting {
        Some(rest) if at_rest(scratch, velocity, &rest) => Some(ContactSettings {
            sweeps: rest.sweeps,
            contact_tolerance: rest.tolerance,
            ..*settings
        }),
        _ => None,
    };
    // Only `Auto` hands a group to the Newton, and never a driven one (see
    // [`escalates`]). One whose sweeps recently fell short goes to the Newton first:
    // the sweeps it would spend first are most of what an escalated step costs.
    let may_hand_over = settings.solver == ContactSolver::Auto && !driven(scratch, velocity);
    let newton_first = settings.newton_first && may_hand_over;
    let first = ContactSettings {
        solver: if newton_first {
            ContactSolver::Newton
        } else {
            settings.solver
        },
        ..*settings
    };
    let mut outcome = newton_steps(set, islands, &first, resting.as_ref(), scratch);
    outcome.newton_first = newton_first;
    if may_hand_over && escalates(&first, &outcome, scratch, rows) {
        // The sweeps left squeezed pairs short (a landing's stack, a pile at a game's
        // step): met over the next steps, their push-out lifts the pile. Solve the
        // group again from the same start by the contact Newton, which meets them.
        start(scratch);
        let newton = ContactSettings {
            solver: ContactSolver::Newton,
            ..*settings
        };
        let again = newton_steps(set, islands, &newton, None, scratch);
        outcome = ContactOutcome {
            iterations: outcome.iterations + again.iterations,
            sweeps: outcome.sweeps + again.sweeps,
            escalated: true,
            ..again
        };
    }
    // Apply: a part whose corrections are absurd (nearly dependent rows asking for a
    // lever's swing) keeps its velocities.
    let limit = settings.max_correction;
    let s = &mut *scratch;
    s.met.clear();
    for part in &mut s.parts {
        let (first, count) = (part.particles.0 as usize, part.particles.1 as usize);
        let corrections = &s.correction[first..first + count];
        part.rejected = corrections
            .iter()
            .any(|c| !c.is_finite() || (limit.is_finite() && c.length() > limit * part.shortest));
        let tolerance = settings.projection.tolerance.max(ROUND_OFF_FLOOR);
        s.met
            .push(!part.rejected && !part.singular && part.residual <= tolerance);
        if part.rejected {
            continue;
        }
        for (j, c) in (first..).zip(corrections) {
            if s.inverse_mass[j] > 0.0 {
                velocity[s.packed[j] as usize] += *c / dt;
            }
        }
    }
    for (row, &c) in s.rows.iter().zip(&s.cut.rows) {
        if let Some(impulse) = impulses.get_mut(c as usize) {
            *impulse = RowImpulse {
                normal: row.mu_n / dt,
                tangent: row.mu_t / dt,
            };
        }
    }
    ContactOutcome {
        converged: s.met.iter().all(|&m| m),
        ..outcome
    }
}

/// A row pushing a squeezed pair out (a pair closer than `keep`: a positive target)
/// that the sweeps leave short by more than this many contact tolerances sends its
/// group to the contact Newton under `Auto`. Measured on the built-in pile, 2 s at
/// 1/300 s, sleeping off: never, 244 J gained; at 0.25, 9.7 J (1.15× the wall time);
/// at 0.05, 2.8 J (1.25×). On any row short, not only a squeezed pair's, the limp fur
/// went to the Newton at most steps and cost 8 times as much.
const ESCALATE_SHORTFALL: f64 = 0.25;

/// Whether `Auto`'s sweeps (no factorization) left a squeezed pair's row of the group
/// in `s` short by more than [`ESCALATE_SHORTFALL`] tolerances. Asked only of a group
/// no driver moves: a driven group gains the driver's energy whatever its rows do, and
/// the fur a driven body drags through itself at 1/60 s leaves such rows short at most
/// steps (3.6× the wall time, nothing gained).
fn escalates(
    settings: &ContactSettings,
    outcome: &ContactOutcome,
    s: &ContactScratch,
    rows: &[ContactRow],
) -> bool {
    let least = ESCALATE_SHORTFALL * settings.contact_tolerance;
    settings.solver == ContactSolver::Auto
        && outcome.factorizations == 0
        && s.rows.iter().zip(&s.cut.rows).any(|(row, &c)| {
            rows.get(c as usize).is_some_and(|r| r.target > 0.0)
                && Sweeps::row_shortfall(s, row) > least
        })
}

/// Whether a particle of the group laid out in `s` is moved by a driver (no inverse
/// mass, a velocity).
fn driven(s: &ContactScratch, velocity: &[DVec2]) -> bool {
    (s.packed.iter().zip(&s.inverse_mass))
        .any(|(&p, &w)| w == 0.0 && velocity[p as usize] != DVec2::ZERO)
}

/// Whether the group laid out in `s` rests: its free particles' mean speed, less the
/// step's fall, below `rest.speed`.
fn at_rest(s: &ContactScratch, velocity: &[DVec2], rest: &Resting) -> bool {
    let (mut sum, mut count) = (0.0, 0usize);
    for (&p, &w) in s.packed.iter().zip(&s.inverse_mass) {
        if w > 0.0 {
            sum += (velocity[p as usize] - rest.fall).length();
            count += 1;
        }
    }
    count > 0 && sum < rest.speed * count as f64
}

/// Number the parts' particles and edges in one numbering, the members in the cut's order, and
/// set up the Newton iteration.
#[allow(clippy::too_many_arguments)]
fn lay_out(
    set: &IslandSet,
    islands: &[u32],
    loose: &[u32],
    position: &[DVec2],
    velocity: &[DVec2],
    inverse_mass: &[f64],
    dt: f64,
    s: &mut ContactScratch,
) {
    s.parts.clear();
    s.packed.clear();
    s.ends.clear();
    s.rest_squared.clear();
    s.predicted_edge.clear();
    s.locked.clear();
    s.incident.clear();
    s.incident_start.clear();
    s.part_of_member.clear();
    s.part_of_member.resize(islands.len() + loose.len(), 0);
    for (part, &member) in s.cut.members.iter().enumerate() {
        s.part_of_member[member as usize] = part as u32;
    }
    s.side_1 = usize::MAX;
    for k in 0..s.cut.members.len() {
        if k == s.cut.side_0 {
            s.side_1 = s.packed.len();
        }
        let i = s.cut.members[k] as usize;
        let Some(&island) = islands.get(i) else {
            let p = loose[i - islands.len()];
            let first = s.packed.len() as u32;
            s.packed.push(p);
            s.incident_start.push(s.incident.len() as u32);
            s.parts.push(Part {
                island: LOOSE,
                particles: (first, 1),
                edges: (s.ends.len() as u32, 0),
                shortest: f64::INFINITY,
                ..Default::default()
            });
            continue;
        };
        with_walk!(IslandView::of(set, island as usize), |edges, walk| {
            lay_out_island(
                i as u32,
                edges,
                walk,
                position,
                velocity,
                inverse_mass,
                dt,
                s,
            )
        })
    }
    s.incident_start.push(s.incident.len() as u32);
    let (n, m) = (s.packed.len(), s.ends.len());
    s.side_1 = s.side_1.min(n);
    s.inverse_mass.clear();
    s.inverse_mass
        .extend(s.packed.iter().map(|&p| inverse_mass[p as usize]));
    for buffer in [&mut s.correction, &mut s.step_start, &mut s.base] {
        buffer.clear();
        buffer.resize(n, DVec2::ZERO);
    }
    s.edge.clear();
    s.edge.resize(m, DVec2::ZERO);
    for buffer in [
        &mut s.constraint,
        &mut s.edge_multiplier,
        &mut s.contact_multiplier,
        &mut s.edge_impulse,
    ] {
        buffer.clear();
        buffer.resize(m, 0.0);
    }
    // Free particles only: a pinned particle may end several islands.
    if s.local_of.len() < inverse_mass.len() {
        s.local_of.resize(inverse_mass.len(), NOT_LOCAL);
    }
    for (j, &p) in s.packed.iter().enumerate() {
        if inverse_mass[p as usize] > 0.0 {
            s.local_of[p as usize] = j as u32;
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn lay_out_island<W: Walk>(
    island: u32,
    edges: &[IslandEdge],
    walk: W,
    position: &[DVec2],
    velocity: &[DVec2],
    inverse_mass: &[f64],
    dt: f64,
    s: &mut ContactScratch,
) {
    let particles = walk.particles(edges);
    let (first, first_edge) = (s.packed.len() as u32, s.ends.len() as u32);
    for j in 0..particles {
        s.packed.push(walk.particle(edges, j) as u32);
    }
    let mut shortest = f64::INFINITY;
    for (k, e) in edges.iter().enumerate() {
        let (a, b) = (e.a as usize, e.b as usize);
        let (ja, jb) = walk.ends(k, particles);
        s.ends.push((first + ja as u32, first + jb as u32));
        let predicted = position[b] - position[a] + dt * (velocity[b] - velocity[a]);
        s.predicted_edge.push(predicted);
        s.rest_squared.push(e.rest_length * e.rest_length);
        s.locked
            .push(edge::locked(predicted, inverse_mass[a] + inverse_mass[b]));
        shortest = shortest.min(e.rest_length);
    }
    for j in 0..particles {
        s.incident_start.push(s.incident.len() as u32);
        let incident = &mut s.incident;
        walk.for_incident(j, edges.len(), |k, sign| {
            incident.push((first_edge + k as u32, sign));
        });
    }
    s.parts.push(Part {
        island,
        particles: (first, particles as u32),
        edges: (first_edge, edges.len() as u32),
        shortest,
        ..Default::default()
    });
}

/// The Newton iterations from Δ = 0 with the localized rows.
fn newton_steps(
    set: &IslandSet,
    islands: &[u32],
    settings: &ContactSettings,
    resting: Option<&ContactSettings>,
    s: &mut ContactScratch,
) -> ContactOutcome {
    let projection = &settings.projection;
    let tolerance = projection.tolerance.max(ROUND_OFF_FLOOR);
    let mut outcome = ContactOutcome::default();
    let mut rows_active = !s.rows.is_empty();
    let mut settings = settings;
    if rows_active
        && settings.solver != ContactSolver::GaussSeidel
        && super::newton::solve(settings, s, &mut outcome).is_some()
    {
        // The rows and edges together; then the edges' polish below, rows frozen.
        rows_active = false;
    } else if let Some(resting) = resting {
        settings = resting;
    }
    let contact_tolerance = settings.contact_tolerance;
    let mut previous_violation = f64::INFINITY;
    let shortest = s.shortest_edge();
    let trust = 0.5 * shortest;
    loop {
        let residual = measure_edges(s);
        let violation = Sweeps::shortfall(s);
        outcome.residual = residual;
        outcome.contact_violation = violation;
        // The polish moves particles by about the residual times an edge: the rows are
        // frozen only once that is no more than they already fall short (the contact
        // tolerance, or where the sweeps stalled above it).
        let polish = EDGE_POLISH.min(contact_tolerance.max(violation) / shortest);
        // The rows are met, or met as well as the sweeps manage once that stops
        // improving: freeze them, and polish the edges alone.
        let settled = residual <= polish
            && (violation <= contact_tolerance || violation > 0.5 * previous_violation);
        // Rows that keep the edges from settling for `rows_give_way` Newton steps (a large
        // step whose linearized rows conflict with the edges) give way: the edges are met
        // exactly, and the collision stage verifies what the rows could not hold.
        let out_of_time = outcome.iterations >= settings.rows_give_way;
        if rows_active && outcome.iterations > 0 && (settled || out_of_time) {
            rows_active = false;
        }
        previous_violation = violation;
        if residual <= tolerance && !rows_active {
            break;
        }
        if outcome.iterations >= projection.max_iterations {
            break;
        }
        outcome.iterations += 1;
        s.step_start.copy_from_slice(&s.correction);
        edge_step(set, islands, s);
        if rows_active {
            let first = outcome.iterations == 1;
            outcome.sweeps +=
                Sweeps::run(set, islands, s, first, settings.sweeps, contact_tolerance);
        } else {
            s.correction.copy_from_slice(&s.base);
            s.contact_multiplier.fill(0.0);
        }
        // Trust region: the linearized edges allow any motion along themselves, and
        // contacts met on that linearization can ask for a lever's swing the edges
        // cannot follow; a shorter step re-linearizes. Measured on the edges' spans, not
        // on the particles: a strand stopped whole in one step (a landing at 1/60 s)
        // moves farther than an edge and bends nothing, and capping its motion took
        // the fine pile 20 Newton steps.
        let longest = longest_swing(&s.ends, |j| s.correction[j] - s.step_start[j]);
        let shrink = if rows_active {
            within_trust(longest, trust)
        } else {
            1.0
        };
        if shrink < 1.0 {
            for (c, start) in s.correction.iter_mut().zip(&s.step_start) {
                *c = *start + shrink * (*c - *start);
            }
            for row in &mut s.rows {
                row.mu_n = row.start_n + shrink * (row.mu_n - row.start_n);
                row.mu_t = row.start_t + shrink * (row.mu_t - row.start_t);
            }
        }
        for k in 0..s.ends.len() {
            let multiplier = s.edge_multiplier[k] - s.contact_multiplier[k];
            s.edge_impulse[k] += shrink * -2.0 * multiplier * s.edge[k].length();
        }
    }
    outcome
}

/// Each part's Newton correction of its edges alone, into `s.base`, its factor kept
/// for the rows' responses.
fn edge_step(set: &IslandSet, islands: &[u32], s: &mut ContactScratch) {
    s.base.copy_from_slice(&s.correction);
    if s.part_factors.len() < s.parts.len() {
        s.part_factors.resize_with(s.parts.len(), Factors::default);
    }
    for p in 0..s.parts.len() {
        let part = s.parts[p];
        if part.island == LOOSE || part.edges.1 == 0 {
            continue;
        }
        let solved = with_walk!(
            IslandView::of(set, islands[part.island as usize] as usize),
            |_, walk| solve_part(p, walk, s)
        );
        if !solved {
            s.parts[p].singular = true;
        }
    }
}

/// Factor part `p`'s system at the current edges (kept in `s.part_factors[p]`) and
/// solve its edge correction; false on a singular system (the part then moves only
/// by its contacts' direct impulses this step).
fn solve_part<W: Walk>(p: usize, walk: W, s: &mut ContactScratch) -> bool {
    let part = s.parts[p];
    let (first, particles) = (part.particles.0 as usize, part.particles.1 as usize);
    let (first_edge, m) = (part.edges.0 as usize, part.edges.1 as usize);
    let island = &mut s.island;
    island.reserve(m, particles);
    island.inverse_mass[..particles].copy_from_slice(&s.inverse_mass[first..first + particles]);
    island.edge[..m].copy_from_slice(&s.edge[first_edge..first_edge + m]);
    island.locked[..m].copy_from_slice(&s.locked[first_edge..first_edge + m]);
    for k in 0..m {
        island.rhs[k] = if island.locked[k] {
            0.0
        } else {
            -s.constraint[first_edge + k]
        };
    }
    // Factor into the part's own storage.
    std::mem::swap(&mut island.factors, &mut s.part_factors[p]);
    let solved = walk.solve(m, ConstraintDirection::EndOfStep, true, island);
    std::mem::swap(&mut island.factors, &mut s.part_factors[p]);
    s.parts[p].factored = solved.is_ok();
    if solved.is_err() {
        s.edge_multiplier[first_edge..first_edge + m].fill(0.0);
        return false;
    }
    s.edge_multiplier[first_edge..first_edge + m].copy_from_slice(&island.rhs[..m]);
    for k in first_edge..first_edge + m {
        let impulse = 2.0 * s.edge_multiplier[k] * s.edge[k];
        let (a, b) = s.ends[k];
        edge::apply(
            &mut s.base,
            &s.inverse_mass,
            (a as usize, b as usize),
            impulse,
        );
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::islands::find_islands;
    use crate::constraints::projection::ProjectionSettings;
    use crate::model::{Edge, PointEdgePair};

    /// A little world: points, edges joining `pairs`, pinned points.
    struct World {
        position: Vec<DVec2>,
        inverse_mass: Vec<f64>,
        set: IslandSet,
    }

    impl World {
        fn new(position: Vec<DVec2>, pairs: &[(u32, u32)], pinned: &[usize]) -> World {
            let mut inverse_mass = vec![1.0; position.len()];
            for &p in pinned {
                inverse_mass[p] = 0.0;
            }
            let edges: Vec<Edge> = pairs
                .iter()
                .map(|&(a, b)| {
                    let length = position[a as usize].distance(position[b as usize]);
                    Edge::new(a, b, length)
                })
                .collect();
            let flags: Vec<bool> = inverse_mass.iter().map(|&w| w == 0.0).collect();
            World {
                set: find_islands(&edges, &flags),
                position,
                inverse_mass,
            }
        }

        /// Project every island and the free particles in none with `rows`.
        fn project(
            &self,
            velocity: &mut [DVec2],
            rows: &[ContactRow],
            impulses: &mut [RowImpulse],
            dt: f64,
            scratch: &mut ContactScratch,
        ) -> ContactOutcome {
            self.project_by(ContactSolver::Newton, velocity, rows, impulses, dt, scratch)
        }

        /// [`World::project`] with the rows' impulses found by `solver`.
        fn project_by(
            &self,
            solver: ContactSolver,
            velocity: &mut [DVec2],
            rows: &[ContactRow],
            impulses: &mut [RowImpulse],
            dt: f64,
            scratch: &mut ContactScratch,
        ) -> ContactOutcome {
            let settings = ContactSettings {
                solver,
                ..settings()
            };
            self.project_with(&settings, velocity, rows, impulses, dt, scratch)
        }

        /// [`World::project`] under `settings`.
        fn project_with(
            &self,
            settings: &ContactSettings,
            velocity: &mut [DVec2],
            rows: &[ContactRow],
            impulses: &mut [RowImpulse],
            dt: f64,
            scratch: &mut ContactScratch,
        ) -> ContactOutcome {
            let islands: Vec<u32> = (0..self.set.islands.len() as u32).collect();
            let in_island: Vec<u32> = self.set.edges.iter().flat_map(|e| [e.a, e.b]).collect();
            let loose: Vec<u32> = (0..self.position.len() as u32)
                .filter(|&p| self.inverse_mass[p as usize] > 0.0 && !in_island.contains(&p))
                .collect();
            project_with_contacts(
                &self.set,
                &islands,
                &loose,
                Bodies::new(&self.position, velocity, &self.inverse_mass),
                rows,
                impulses,
                dt,
                settings,
                scratch,
            )
        }

        /// Project with fresh buffers; the projection converged, every edge is exact
        /// and every row is met.
        fn project_and_check(
            &self,
            velocity: &mut [DVec2],
            rows: &[ContactRow],
            impulses: &mut [RowImpulse],
            dt: f64,
        ) {
            let outcome =
                self.project(velocity, rows, impulses, dt, &mut ContactScratch::default());
            assert!(outcome.converged, "{outcome:?}");
            assert!(self.max_relative_error(velocity, dt) < 1e-12);
            assert!(shortfall(rows, velocity, dt) <= TOLERANCE);
        }

        fn max_relative_error(&self, velocity: &[DVec2], dt: f64) -> f64 {
            let end = |i: u32| self.position[i as usize] + dt * velocity[i as usize];
            self.set
                .edges
                .iter()
                .map(|e| (end(e.b).distance(end(e.a)) - e.rest_length).abs() / e.rest_length)
                .fold(0.0, f64::max)
        }

        fn momentum(&self, velocity: &[DVec2]) -> DVec2 {
            (velocity.iter().zip(&self.inverse_mass))
                .filter(|(_, w)| **w > 0.0)
                .map(|(v, w)| *v / *w)
                .sum()
        }
    }

    const TOLERANCE: f64 = 1e-9;

    fn settings() -> ContactSettings {
        ContactSettings {
            resting: None,
            projection: ProjectionSettings {
                tolerance: 1e-13,
                max_iterations: 30,
                direction: ConstraintDirection::EndOfStep,
                max_restep_depth: 0,
            },
            sweeps: 200,
            contact_tolerance: TOLERANCE,
            max_correction: f64::INFINITY,
            rows_give_way: 15,
            solver: ContactSolver::default(),
            newton_first: false,
        }
    }

    /// Point `p` against edge (q, r) at `alpha` along `normal`, asked to end the step
    /// no closer than `gap` along it.
    fn row(world: &World, pair: PointEdgePair, normal: DVec2, gap: f64, dt: f64) -> ContactRow {
        let x = &world.position;
        let start = normal.dot(x[pair.p] - x[pair.q].lerp(x[pair.r], pair.alpha));
        let mut row = ContactRow::point_edge(pair, normal, &vec![DVec2::ZERO; x.len()]);
        row.target = (gap - start) / dt;
        row
    }

    fn pair(p: usize, q: usize, r: usize, alpha: f64) -> PointEdgePair {
        PointEdgePair { p, q, r, alpha }
    }

    /// How far each row falls short of its target, as a distance per step.
    fn shortfall(rows: &[ContactRow], velocity: &[DVec2], dt: f64) -> f64 {
        rows.iter()
            .map(|r| (r.target - r.normal_velocity(velocity)) * dt)
            .fold(0.0, f64::max)
    }

    /// Strand A (0..5) hanging vertically with its lowest particle just above the
    /// middle of strand B (5..10), lying flat.
    fn two_strands() -> World {
        let mut position: Vec<DVec2> = (0..5)
            .map(|i| DVec2::new(0.43, 0.006 + 0.02 * i as f64))
            .collect();
        position.extend((0..5).map(|i| DVec2::new(0.40 + 0.02 * i as f64, 0.0)));
        let pairs = [
            (0, 1),
            (1, 2),
            (2, 3),
            (3, 4),
            (5, 6),
            (6, 7),
            (7, 8),
            (8, 9),
        ];
        World::new(position, &pairs, &[])
    }

    #[test]
    fn two_strands_in_contact_push_each_other_and_keep_their_momentum() {
        // Strand A (0..5) hangs vertically with its lowest particle just above the
        // middle of strand B (5..10), lying flat; A falls, B rises to meet it.
        let world = two_strands();
        let dt = 0.01;
        let mut velocity = vec![DVec2::new(0.3, -1.0); 5];
        velocity[1] = DVec2::new(0.3, -2.0);
        velocity.extend([DVec2::new(-0.1, 0.4); 5]);
        let rows = [row(&world, pair(0, 6, 7, 0.5), DVec2::Y, 0.004, dt)];
        let before = velocity.clone();
        let mut impulses = [RowImpulse::default()];
        world.project_and_check(&mut velocity, &rows, &mut impulses, dt);
        assert!(impulses[0].normal > 0.0);
        let (after, start) = (world.momentum(&velocity), world.momentum(&before));
        assert!((after - start).length() < 1e-12, "{after} against {start}");
        // Both moved: A held up, B pushed down.
        assert!(velocity[0].y > before[0].y && velocity[6].y < before[6].y);
    }

    #[test]
    fn only_rows_that_take_an_impulse_get_room_for_their_responses() {
        // Strand A (0..5) falls onto the middle of strand B (5..10) as above; a second
        // row between A's top and B's end asks for a gap they already keep, so it
        // never takes an impulse and never forms its responses.
        let world = two_strands();
        let dt = 0.01;
        let mut velocity = vec![DVec2::new(0.0, -1.0); 5];
        velocity.extend([DVec2::ZERO; 5]);
        let rows = [
            row(&world, pair(0, 6, 7, 0.5), DVec2::Y, 0.004, dt),
            row(&world, pair(4, 8, 9, 0.5), DVec2::Y, 0.0, dt),
        ];
        let mut impulses = [RowImpulse::default(); 2];
        let mut scratch = ContactScratch::default();
        let outcome = world.project_by(
            ContactSolver::GaussSeidel,
            &mut velocity,
            &rows,
            &mut impulses,
            dt,
            &mut scratch,
        );
        assert!(outcome.converged, "{outcome:?}");
        assert!(impulses[0].normal > 0.0 && impulses[1] == RowImpulse::default());
        // The first row's two links: both strands' 5 particles and 4 edges, normal and
        // tangent each.
        // Not cut: every row is in the last bank.
        assert_eq!(scratch.banks[2].placed, (2 * (5 + 5), 2 * (4 + 4)));
        assert!(world.max_relative_error(&velocity, dt) < 1e-12);
    }

    #[test]
    fn a_strand_landing_flat_at_a_games_step_is_stopped_in_a_few_newton_steps() {
        // A strand of 15 particles 5.6 mm apart lying flat 6 mm over a pinned floor edge
        // (2 mm outside the 4 mm cushion) and falling at 4 m/s, at 1/60 s: each step it
        // would sink 67 mm, twelve of its edges. Carried whole, it bends nothing: the trust region (on the edges'
        // spans) lets each Newton step stop it all at once. Bounded by each particle's
        // own motion it took one step per half an edge, past the rows' give-way.
        let mut position: Vec<DVec2> = (0..15)
            .map(|i| DVec2::new(0.0056 * i as f64, 0.006))
            .collect();
        position.extend([DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0)]);
        let mut pairs: Vec<(u32, u32)> = (0..14).map(|i| (i, i + 1)).collect();
        pairs.push((15, 16));
        let world = World::new(position, &pairs, &[15, 16]);
        let dt = 1.0 / 60.0;
        for solver in [ContactSolver::GaussSeidel, ContactSolver::Newton] {
            let mut velocity = vec![DVec2::new(0.0, -4.0); 17];
            (velocity[15], velocity[16]) = (DVec2::ZERO, DVec2::ZERO);
            let rows: Vec<ContactRow> = (0..15)
                .map(|p| {
                    let alpha = (world.position[p].x + 1.0) / 2.0;
                    row(&world, pair(p, 15, 16, alpha), DVec2::Y, 0.004, dt)
                })
                .collect();
            let mut impulses = vec![RowImpulse::default(); rows.len()];
            let outcome = world.project_by(
                solver,
                &mut velocity,
                &rows,
                &mut impulses,
                dt,
                &mut ContactScratch::default(),
            );
            assert!(outcome.converged, "{solver:?}: {outcome:?}");
            assert!(outcome.iterations <= 4, "{solver:?}: {outcome:?}");
            assert!(world.max_relative_error(&velocity, dt) < 1e-12);
            assert!(shortfall(&rows, &velocity, dt) <= TOLERANCE);
            // Stopped where the rows hold it, not thrown back up.
            for v in &velocity[..15] {
                assert!(
                    (v.y - (0.004 - 0.006) / dt).abs() * dt < 1e-6,
                    "{solver:?}: {v}"
                );
            }
        }
    }

    #[test]
    fn a_contact_holds_a_strand_pushed_into_it_and_lets_go_of_one_pulled_away() {
        // A strand lying on a floor (a pinned edge, particles 6 and 7), touching it at
        // its first particle; its middle particle kicked down, or up.
        let mut position: Vec<DVec2> = (0..6).map(|i| DVec2::new(0.1 * i as f64, 0.0)).collect();
        position.extend([DVec2::new(-0.5, -0.004), DVec2::new(0.5, -0.004)]);
        let pairs = [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (6, 7)];
        let world = World::new(position, &pairs, &[6, 7]);
        let dt = 0.01;
        for kick in [-2.0, 2.0] {
            let mut velocity = vec![DVec2::ZERO; 8];
            velocity[2] = DVec2::new(0.0, kick);
            let rows = [row(&world, pair(0, 6, 7, 0.5), DVec2::Y, 0.004, dt)];
            let mut impulses = [RowImpulse::default()];
            world.project_and_check(&mut velocity, &rows, &mut impulses, dt);
            if kick < 0.0 {
                assert!(impulses[0].normal > 0.0);
                assert!(
                    velocity[0].y.abs() * dt <= 2.0 * TOLERANCE,
                    "{}",
                    velocity[0].y
                );
            } else {
                // Pulled up, away from the floor: the contact lets go.
                assert_eq!(impulses[0].normal, 0.0);
                assert!(velocity[0].y > 1e-6, "{}", velocity[0].y);
            }
        }
    }

    #[test]
    fn friction_stops_sliding_inside_the_cone_and_slows_it_outside() {
        // A loose particle pressed into a pinned floor edge while sliding along it:
        // the normal impulse stops the approach, friction takes up to 0.3 of it off
        // the sliding (Coulomb's law on the step's impulses).
        let position = vec![
            DVec2::new(0.0, 0.004),
            DVec2::new(-1.0, 0.0),
            DVec2::new(1.0, 0.0),
        ];
        let world = World::new(position, &[(1, 2)], &[1, 2]);
        let dt = 0.01;
        for (slide, sticks) in [(0.25, true), (0.5, false)] {
            let mut velocity = vec![DVec2::new(slide, -1.0), DVec2::ZERO, DVec2::ZERO];
            let mut rows = [row(&world, pair(0, 1, 2, 0.5), DVec2::Y, 0.004, dt)];
            rows[0].friction = 0.3;
            let mut impulses = [RowImpulse::default()];
            world.project(
                &mut velocity,
                &rows,
                &mut impulses,
                dt,
                &mut ContactScratch::default(),
            );
            assert!((velocity[0].y * dt).abs() <= TOLERANCE);
            assert!((impulses[0].normal - 1.0).abs() < 1e-6, "{:?}", impulses[0]);
            if sticks {
                assert!(velocity[0].x.abs() < 1e-6, "{}", velocity[0].x);
            } else {
                assert!((velocity[0].x - 0.2).abs() < 1e-6, "{}", velocity[0].x);
                assert!((impulses[0].tangent.abs() - 0.3 * impulses[0].normal).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn a_particle_in_a_corner_gets_the_impulses_of_the_exact_contact_problem() {
        // A loose particle driven into the corner of two pinned walls at 60° to each
        // other: two rows that share it. Its contact problem is a 2 × 2 complementarity
        // problem, solved here by trying each active set.
        let corner = DVec2::ZERO;
        let left = DVec2::from_angle(150f64.to_radians());
        let right = DVec2::X;
        let normals = [left.perp().normalize() * -1.0, right.perp()];
        let x = corner + 0.01 * DVec2::new(-0.3, 1.0);
        let position = vec![x, corner, corner + left, corner + right];
        let world = World::new(position, &[(1, 2), (1, 3)], &[1, 2, 3]);
        let dt = 0.01;
        let push = -2.0 * (normals[0] + normals[1]);
        let mut velocity = vec![push, DVec2::ZERO, DVec2::ZERO, DVec2::ZERO];
        let rows: Vec<ContactRow> = [(2, normals[0]), (3, normals[1])]
            .iter()
            .map(|&(r, n)| {
                let alpha = (x - corner).dot(world.position[r] - corner)
                    / (world.position[r] - corner).length_squared();
                row(&world, pair(0, 1, r, alpha), n, 0.004, dt)
            })
            .collect();
        let mut impulses = [RowImpulse::default(); 2];
        world.project(
            &mut velocity,
            &rows,
            &mut impulses,
            dt,
            &mut ContactScratch::default(),
        );
        // Brute force: S = N W Nᵀ (unit mass), q = N v − target.
        let s = |a: usize, b: usize| rows[a].normal.dot(rows[b].normal);
        let q: Vec<f64> = rows.iter().map(|r| r.normal.dot(push) - r.target).collect();
        let mut best = None;
        for active in 0..4u32 {
            let on = |c: usize| active & (1 << c) != 0;
            let mu = match (on(0), on(1)) {
                (false, false) => [0.0, 0.0],
                (true, false) => [-q[0] / s(0, 0), 0.0],
                (false, true) => [0.0, -q[1] / s(1, 1)],
                (true, true) => {
                    let det = s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0);
                    [
                        (-q[0] * s(1, 1) + q[1] * s(0, 1)) / det,
                        (-q[1] * s(0, 0) + q[0] * s(1, 0)) / det,
                    ]
                }
            };
            let w = [0, 1].map(|c| q[c] + s(c, 0) * mu[0] + s(c, 1) * mu[1]);
            let feasible = (0..2).all(|c| mu[c] >= -1e-12 && w[c] >= -1e-12);
            if feasible {
                best = Some(mu);
            }
        }
        let exact = best.expect("a solution");
        for c in 0..2 {
            assert!(
                (impulses[c].normal - exact[c]).abs() < 1e-6,
                "{impulses:?} against {exact:?}"
            );
        }
        assert!(exact[0] > 0.0 && exact[1] > 0.0, "both walls push");
    }

    #[test]
    fn a_tree_in_contact_keeps_every_edge_and_its_momentum() {
        // A Y: a stem 0–1–2 forking at 2 into 3–4 and 5–6; a loose particle 7 falls
        // onto the middle of edge 3–4.
        let position = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(0.0, 0.05),
            DVec2::new(0.0, 0.1),
            DVec2::new(-0.04, 0.13),
            DVec2::new(-0.08, 0.16),
            DVec2::new(0.04, 0.13),
            DVec2::new(0.08, 0.16),
            DVec2::new(-0.06, 0.15),
        ];
        let pairs = [(0, 1), (1, 2), (2, 3), (3, 4), (2, 5), (5, 6)];
        let world = World::new(position, &pairs, &[]);
        let dt = 0.005;
        let mut velocity = vec![DVec2::new(0.2, 0.1); 8];
        velocity[7] = DVec2::new(0.3, -3.0);
        let normal = (world.position[4] - world.position[3]).perp().normalize();
        let normal = if normal.y < 0.0 { -normal } else { normal };
        let rows = [row(&world, pair(7, 3, 4, 0.5), normal, 0.004, dt)];
        let before = velocity.clone();
        let mut impulses = [RowImpulse::default()];
        world.project_and_check(&mut velocity, &rows, &mut impulses, dt);
        let (after, start) = (world.momentum(&velocity), world.momentum(&before));
        assert!((after - start).length() < 1e-12, "{after} against {start}");
    }

    #[test]
    fn the_impulses_returned_warm_start_the_same_problem_to_the_same_answer() {
        // A strand lying across three pinned posts, pushed down onto them.
        let mut position: Vec<DVec2> = (0..9).map(|i| DVec2::new(0.02 * i as f64, 0.004)).collect();
        position.extend([
            DVec2::new(0.03, 0.0),
            DVec2::new(0.05, 0.0),
            DVec2::new(0.11, 0.0),
            DVec2::new(0.13, 0.0),
        ]);
        let pairs = [
            (0, 1),
            (1, 2),
            (2, 3),
            (3, 4),
            (4, 5),
            (5, 6),
            (6, 7),
            (7, 8),
            (9, 10),
            (11, 12),
        ];
        let world = World::new(position, &pairs, &[9, 10, 11, 12]);
        let dt = 0.002;
        let start: Vec<DVec2> = (0..13)
            .map(|i| {
                if i < 9 {
                    DVec2::new(0.1, -1.0 - 0.1 * i as f64)
                } else {
                    DVec2::ZERO
                }
            })
            .collect();
        let rows: Vec<ContactRow> = [(2, 9, 10), (6, 11, 12)]
            .iter()
            .map(|&(p, q, r)| row(&world, pair(p, q, r, 0.5), DVec2::Y, 0.004, dt))
            .collect();
        for solver in [ContactSolver::GaussSeidel, ContactSolver::Newton] {
            let mut scratch = ContactScratch::default();
            let mut cold = start.clone();
            let mut impulses = vec![RowImpulse::default(); 2];
            let project = |v: &mut [DVec2], i: &mut [RowImpulse], s: &mut ContactScratch| {
                world.project_by(solver, v, &rows, i, dt, s)
            };
            let first = project(&mut cold, &mut impulses, &mut scratch);
            let mut warm = start.clone();
            let second = project(&mut warm, &mut impulses, &mut scratch);
            assert!(first.converged && second.converged);
            // The sweeps start from the answer. Newton's first problem is shifted by
            // it, but its steps are set by the edges' turning, the same from either
            // start: it only has to land on the same answer.
            if solver == ContactSolver::GaussSeidel {
                assert!(second.sweeps < first.sweeps, "{second:?} against {first:?}");
            }
            for (a, b) in cold.iter().zip(&warm) {
                assert!(
                    (*a - *b).length() * dt < 10.0 * TOLERANCE,
                    "{solver:?}: {a} against {b}"
                );
            }
            assert!(world.max_relative_error(&warm, dt) < 1e-12);
        }
    }

    #[test]
    fn a_large_projection_is_cut_and_gives_the_same_bits_on_one_thread_or_two() {
        // A stack of 230 strands of 10 particles, 4 mm apart, on a pinned floor
        // strand, falling and sliding: every particle of a strand has a row (with
        // friction) against the edge below it, 2 290 rows in all, enough to be cut.
        let (strands, particles) = (231, 10);
        let mut position = Vec::new();
        let mut pairs = Vec::new();
        for s in 0..strands {
            let first = position.len() as u32;
            position.extend((0..particles).map(|i| DVec2::new(0.01 * i as f64, 0.004 * s as f64)));
            pairs.extend((0..particles as u32 - 1).map(|i| (first + i, first + i + 1)));
        }
        let world = World::new(position, &pairs, &(0..particles).collect::<Vec<_>>());
        let dt = 0.002;
        let mut rows = Vec::new();
        for s in 1..strands {
            for i in 0..particles {
                let (p, below) = (
                    s * particles + i,
                    (s - 1) * particles + i.min(particles - 2),
                );
                let mut r = row(&world, pair(p, below, below + 1, 0.5), DVec2::Y, 0.004, dt);
                r.friction = 0.3;
                rows.push(r);
            }
        }
        let start: Vec<DVec2> = (0..strands * particles)
            .map(|p| match p / particles {
                0 => DVec2::ZERO,
                s => DVec2::new(0.2 * (s % 3) as f64, -0.5 - 0.001 * s as f64),
            })
            .collect();
        for solver in [ContactSolver::GaussSeidel, ContactSolver::Newton] {
            let mut results = Vec::new();
            for threads in [1, 2] {
                let mut scratch = ContactScratch::default();
                scratch.set_threads(threads);
                let mut velocity = start.clone();
                let mut impulses = vec![RowImpulse::default(); rows.len()];
                let outcome = world.project_by(
                    solver,
                    &mut velocity,
                    &rows,
                    &mut impulses,
                    dt,
                    &mut scratch,
                );
                let (end_0, end_1) = scratch.cut.row_ends;
                assert!(
                    end_0 > 0 && end_1 > end_0 && end_1 < rows.len(),
                    "cut: {end_0} {end_1}"
                );
                assert!(outcome.converged, "{solver:?}: {outcome:?}");
                assert!(world.max_relative_error(&velocity, dt) < 1e-12);
                assert!(
                    impulses
                        .iter()
                        .all(|i| i.normal >= 0.0 && i.tangent.is_finite())
                );
                assert!(impulses.iter().filter(|i| i.normal > 0.0).count() > rows.len() / 2);
                let velocity_bits = |v: &[DVec2]| -> Vec<[u64; 2]> {
                    v.iter().map(|v| v.to_array().map(f64::to_bits)).collect()
                };
                let impulse_bits: Vec<[u64; 2]> = (impulses.iter())
                    .map(|i| [i.normal.to_bits(), i.tangent.to_bits()])
                    .collect();
                results.push((velocity_bits(&velocity), impulse_bits, outcome.sweeps));
            }
            assert!(
                results[0] == results[1],
                "{solver:?}: one thread and two differ"
            );
        }
    }

    #[test]
    fn a_long_strand_folded_onto_itself_is_projected_by_newton_no_farther_than_by_the_sweeps() {
        // One strand of 200 particles folded in two, its upper half falling onto its
        // lower half lying on a pinned floor: every row couples two far apart stretches
        // of the same strand (a response as long as the strand, for the sweeps; three
        // particles, for Newton). Frictionless: both must meet every row and edge.
        let n = 200;
        let half = n / 2;
        let mut position: Vec<DVec2> = (0..half)
            .map(|i| DVec2::new(0.01 * i as f64, 0.004))
            .collect();
        position.push(DVec2::new(0.01 * half as f64 + 0.002, 0.006));
        position.extend((1..half).map(|i| DVec2::new(0.01 * (half - i) as f64 - 0.005, 0.0085)));
        let mut pairs: Vec<(u32, u32)> = (0..n as u32 - 1).map(|i| (i, i + 1)).collect();
        position.extend([DVec2::new(-1.0, 0.0), DVec2::new(2.0, 0.0)]);
        pairs.push((n as u32, n as u32 + 1));
        let world = World::new(position, &pairs, &[n, n + 1]);
        let dt = 1.0 / 300.0;
        let mut rows = Vec::new();
        // The lower half on the floor, and the upper half on the lower half.
        for p in 0..half {
            rows.push(row(&world, pair(p, n, n + 1, 0.5), DVec2::Y, 0.004, dt));
        }
        for p in half + 1..n {
            let x = world.position[p].x;
            let below = ((x / 0.01).floor() as usize).min(half - 2);
            let alpha = (x - 0.01 * below as f64) / 0.01;
            rows.push(row(
                &world,
                pair(p, below, below + 1, alpha),
                DVec2::Y,
                0.004,
                dt,
            ));
        }
        let start: Vec<DVec2> = (0..n + 2)
            .map(|p| {
                if p >= half && p < n {
                    DVec2::new(0.1, -0.6)
                } else if p < n {
                    DVec2::new(0.1, -0.05)
                } else {
                    DVec2::ZERO
                }
            })
            .collect();
        let mut results = Vec::new();
        for solver in [ContactSolver::GaussSeidel, ContactSolver::Newton] {
            let mut velocity = start.clone();
            let mut impulses = vec![RowImpulse::default(); rows.len()];
            let settings = ContactSettings {
                solver,
                sweeps: 4000,
                contact_tolerance: 1e-10,
                ..settings()
            };
            let outcome = world.project_with(
                &settings,
                &mut velocity,
                &rows,
                &mut impulses,
                dt,
                &mut ContactScratch::default(),
            );
            assert!(outcome.converged, "{solver:?}: {outcome:?}");
            assert!(world.max_relative_error(&velocity, dt) < 1e-12);
            assert!(shortfall(&rows, &velocity, dt) <= 1e-9, "{solver:?}");
            let (after, before) = (world.momentum(&velocity), world.momentum(&start));
            // The floor takes the strand's weight; sideways, nothing acts.
            assert!(
                (after.x - before.x).abs() < 1e-12,
                "{solver:?}: {after} {before}"
            );
            results.push((velocity, outcome));
        }
        let (swept, newton) = (&results[0], &results[1]);
        assert!(newton.1.factorizations > 0 && swept.1.sweeps > 0);
        // Both end on the edges' manifold with the rows met; the projection is the
        // motion nearest the prediction in kinetic energy, and Newton, minimizing just
        // that, ends no farther from it than the sweeps do.
        let distance = |v: &[DVec2]| -> f64 {
            (v.iter().zip(&start).zip(&world.inverse_mass))
                .filter(|(_, w)| **w > 0.0)
                .map(|((v, s), w)| (*v - *s).length_squared() / w)
                .sum()
        };
        let (d_swept, d_newton) = (distance(&swept.0), distance(&newton.0));
        assert!(
            d_newton <= d_swept * (1.0 + 1e-6),
            "{d_newton} against {d_swept}"
        );
    }

    #[test]
    fn rows_that_cannot_all_be_met_are_frozen_and_the_edges_still_exact() {
        // The middle particle of a strand squeezed between two pinned walls 5 mm apart,
        // each asking for 4 mm: no impulses meet both rows, and Gauss–Seidel only trades
        // one for the other. Once that stops improving the rows are frozen, well before
        // they would give way, and the edges are polished exact.
        let mut position: Vec<DVec2> = (0..5).map(|i| DVec2::new(0.02 * i as f64, 0.0)).collect();
        position.extend([
            DVec2::new(0.03, -0.0025),
            DVec2::new(0.05, -0.0025),
            DVec2::new(0.05, 0.0025),
            DVec2::new(0.03, 0.0025),
        ]);
        let pairs = [(0, 1), (1, 2), (2, 3), (3, 4), (5, 6), (7, 8)];
        let world = World::new(position, &pairs, &[5, 6, 7, 8]);
        let dt = 0.002;
        let mut velocity = vec![DVec2::new(0.05, 0.0); 9];
        for pinned in &mut velocity[5..] {
            *pinned = DVec2::ZERO;
        }
        let rows = [
            row(&world, pair(2, 5, 6, 0.5), DVec2::Y, 0.004, dt),
            row(&world, pair(2, 7, 8, 0.5), -DVec2::Y, 0.004, dt),
        ];
        let mut impulses = [RowImpulse::default(); 2];
        let outcome = world.project(
            &mut velocity,
            &rows,
            &mut impulses,
            dt,
            &mut ContactScratch::default(),
        );
        assert!(outcome.contact_violation > 1e-3, "{outcome:?}");
        assert!(outcome.converged, "{outcome:?}");
        assert!(outcome.iterations < settings().rows_give_way, "{outcome:?}");
        // Frozen once they stalled and the edges were within what the rows fall short:
        // after the second Newton step's sweeps, not held until the edges are within the
        // contact tolerance.
        assert!(outcome.sweeps <= 2 * settings().sweeps, "{outcome:?}");
        assert!(velocity.iter().all(|v| v.is_finite()));
        assert!(world.max_relative_error(&velocity, dt) < 1e-12);
    }

    /// Six strands of one edge (1 cm) stacked 3 mm apart on a pinned floor edge, all
    /// falling at 1 m/s, each pair of layers asked out to 4 mm (squeezed: positive
    /// targets), at 1/60 s; with `floor_velocity` the floor is driven.
    fn squeezed_stack(floor_velocity: DVec2) -> (World, Vec<DVec2>, Vec<ContactRow>) {
        let layers = 6;
        let mut position = Vec::new();
        for k in 0..layers {
            let y = 0.003 * (k + 1) as f64;
            position.extend([DVec2::new(0.0, y), DVec2::new(0.01, y)]);
        }
        let floor = 2 * layers;
        position.extend([DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0)]);
        let mut pairs: Vec<(u32, u32)> = (0..layers as u32).map(|k| (2 * k, 2 * k + 1)).collect();
        pairs.push((floor as u32, floor as u32 + 1));
        let world = World::new(position, &pairs, &[floor, floor + 1]);
        let dt = 1.0 / 60.0;
        let mut rows = Vec::new();
        for k in 0..layers {
            for (i, alpha) in [(0, 0.0), (1, 1.0)] {
                let p = 2 * k + i;
                let below = if k == 0 {
                    pair(
                        p,
                        floor,
                        floor + 1,
                        (0.5 + 0.5 * world.position[p].x).clamp(0.0, 1.0),
                    )
                } else {
                    pair(p, 2 * (k - 1), 2 * (k - 1) + 1, alpha)
                };
                rows.push(row(&world, below, DVec2::Y, 0.004, dt));
            }
        }
        let mut velocity = vec![DVec2::new(0.0, -1.0); 2 * layers];
        velocity.extend([floor_velocity; 2]);
        (world, velocity, rows)
    }

    #[test]
    fn a_newton_that_keeps_its_analysis_answers_as_a_fresh_one_bit_for_bit() {
        // The squeezed stack with all its rows (A) and with its top layer's rows gone
        // (B: another pattern), projected in turn by one scratch, which keeps the last
        // pattern's analysis and plan, and each by a fresh scratch.
        let dt = 1.0 / 60.0;
        let (world, start, rows) = squeezed_stack(DVec2::ZERO);
        let fewer = &rows[..rows.len() - 2];
        let project = |rows: &[ContactRow], scratch: &mut ContactScratch| {
            let (mut velocity, mut impulses) =
                (start.clone(), vec![RowImpulse::default(); rows.len()]);
            let outcome = world.project(&mut velocity, rows, &mut impulses, dt, scratch);
            assert!(outcome.factorizations > 0, "{outcome:?}");
            let bits = |v: &[DVec2]| {
                v.iter()
                    .flat_map(|v| [v.x.to_bits(), v.y.to_bits()])
                    .collect::<Vec<_>>()
            };
            (bits(&velocity), impulses)
        };
        let fresh_a = project(&rows, &mut ContactScratch::default());
        let fresh_b = project(fewer, &mut ContactScratch::default());
        assert_ne!(fresh_a.0, fresh_b.0);
        let mut kept = ContactScratch::default();
        for (rows, fresh) in [
            (&rows[..], &fresh_a),
            (&rows[..], &fresh_a),
            (fewer, &fresh_b),
            (&rows[..], &fresh_a),
        ] {
            assert_eq!(&project(rows, &mut kept), fresh);
        }
    }

    #[test]
    fn sweeps_that_leave_a_squeezed_pair_short_hand_the_group_to_the_newton() {
        let dt = 1.0 / 60.0;
        let few_sweeps = ContactSettings {
            solver: ContactSolver::Auto,
            sweeps: 1,
            ..settings()
        };
        let project = |floor: DVec2, settings: &ContactSettings| {
            let (world, mut velocity, rows) = squeezed_stack(floor);
            assert!(rows.iter().all(|r| r.target > 0.0));
            let mut impulses = vec![RowImpulse::default(); rows.len()];
            let outcome = world.project_with(
                settings,
                &mut velocity,
                &rows,
                &mut impulses,
                dt,
                &mut ContactScratch::default(),
            );
            assert!(world.max_relative_error(&velocity, dt) < 1e-12);
            (outcome, shortfall(&rows, &velocity, dt))
        };
        // The sweeps alone fall far short of the stack; the Newton meets it.
        let swept = ContactSettings {
            solver: ContactSolver::GaussSeidel,
            ..few_sweeps
        };
        let (outcome, short) = project(DVec2::ZERO, &swept);
        assert!(!outcome.escalated && short > 100.0 * TOLERANCE, "{short}");
        let (outcome, short) = project(DVec2::ZERO, &few_sweeps);
        assert!(
            outcome.escalated && outcome.factorizations > 0,
            "{outcome:?}"
        );
        assert!(short <= TOLERANCE, "{short}");
        // Told to (a recent escalation), the Newton is tried first: no sweep.
        let first = ContactSettings {
            newton_first: true,
            ..few_sweeps
        };
        let (outcome, short) = project(DVec2::ZERO, &first);
        assert!(outcome.newton_first && !outcome.escalated && outcome.sweeps == 0);
        assert!(short <= TOLERANCE, "{short}");
        // A driven floor: the group's energy is the driver's, and the sweeps keep it.
        let driven = DVec2::new(0.1, 0.0);
        let (outcome, short) = project(driven, &few_sweeps);
        assert!(!outcome.escalated && outcome.factorizations == 0 && short > TOLERANCE);
        let (outcome, _) = project(driven, &first);
        assert!(!outcome.newton_first && outcome.factorizations == 0);
    }
}
