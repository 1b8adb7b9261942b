//! The contact Newton: a contact projection's rows and edges solved together by Newton's
//! method on one sparse system, so that a row costs its own three particles whatever
//! the length of the strands it touches.
//!
//! Each row is two rows of Coulomb's cone, the cone's edges `e± = (1, ±μ) / √(1 + μ²)`
//! in the row's (normal, tangent) plane: a contact pushes along `n ± μ t` with impulses
//! `λ± ≥ 0`, so its impulse is inside the cone by construction, and it holds `u± =
//! e±·(u_n, u_t) ≥ 0`, `u_n` how far the pair ends clear of its target and `u_t` how far
//! it slides (a sticking contact meets both edges, `u_n = u_t = 0`; a sliding one the
//! edge behind its sliding, ending `μ |u_t|` clear: Anitescu's convex cone). The
//! corrections Δ minimize, over the motions the edges allow,
//!
//! `½ Δᵀ M Δ + Σ_rows Σ± ½ k min(0, u± − λ̄± / k)²`,
//!
//! `k` a stiffness a thousand times the row's own mass and `λ̄±` the impulses of the
//! last solve (an augmented Lagrangian: a pressed row converges onto its target, not
//! `λ/k` short of it). The objective is convex, piecewise quadratic and strictly convex
//! whatever the rows: rows that are exact combinations of others (a tenth of a mat of
//! hair's, where Gauss–Seidel stalls and a textbook active set cycles) leave the motion
//! unique.
//!
//! Each Newton step linearizes the edges at the iterate and solves `[H Jᵀ; J 0]`
//! (`kkt`) twice with one factorization: for the full step, and for the step
//! that only meets the edges. The edges' part is taken whole; the rest is taken whole
//! for a few steps (the rows' states then follow the iterate, as in a primal–dual
//! active set), then with an exact line search on the objective (MuJoCo's primal
//! Newton, Todorov 2014, with hard edges). The iterate is kept as impulses, every row's
//! and edge's equal and opposite on its particles, and Δ = W P: momentum is kept to
//! round-off at every step. Once the rows are met and the edges nearly so, the contact
//! projection's last Newton steps polish the edges alone (`projection`).

mod cone;
mod kkt;
mod line_search;
pub(super) mod scratch;

use bevy::math::DVec2;

use self::cone::{
    cone, edges, impulse, pull, push, row_motion, row_values, unknown_motion, unknown_vector,
};
use self::kkt::{KktInput, NONE, RowModel};
use self::line_search::Line;
use self::scratch::NewtonScratch;
use crate::constraints::projection::ROUND_OFF_FLOOR;
use crate::contact::local_row::LocalRow;
use crate::contact::scratch::{ContactScratch, longest_swing, measure_edges, within_trust};
use crate::contact::settings::{ContactOutcome, ContactSettings, ContactSolver};

/// A row's contact stiffness over its own mass `1 / Σ cᵢ² wᵢ`: soft enough that a step
/// pressing a new row is not stopped at it, stiff enough that a row pressed by impulse
/// λ gives `λ / k`, a thousandth of the motion it stops, before its shift takes it up.
const STIFFNESS: f64 = 1e3;

/// Newton steps taken whole (up to the trust region) after each new shift, before the
/// line search guards them.
const FULL_STEPS: u32 = 6;

/// Newton steps without the rows' shortfall halving after which they are left as they
/// are.
const STALL: u32 = 4;

/// Rows this many tolerances from Coulomb's law are left where they are once the whole
/// steps are done (the sweeps stalled at two to seven).
const CLOSE_ENOUGH: f64 = 4.0;

/// Row `r`'s cone values at corrections `delta`, shifted by its impulses and with its
/// normal value lifted by what its sliding asked of it last time (see [`run`]).
fn cone_values(row: &LocalRow, r: usize, w: &NewtonScratch, delta: &[DVec2]) -> [f64; 2] {
    let (un, ut) = row_values(row, delta);
    let un = un + w.lift[r];
    let e = cone(row.friction);
    [0, 1].map(|x| e[x].0 * un + e[x].1 * ut - w.shift[r][x])
}

/// Solve the rows and edges of the laid-out contact projection in `s` together, from
/// the rows' warm-start impulses: `s.correction`, the rows' impulses and the edges'
/// impulses hold the result. Returns whether the rows were met, or `None`, touching
/// nothing, when the sweeps would cost less (see [`prefers_sweeps`]).
pub(super) fn solve(
    settings: &ContactSettings,
    s: &mut ContactScratch,
    outcome: &mut ContactOutcome,
) -> Option<bool> {
    let mut newton = std::mem::take(&mut s.newton);
    let met = run(settings, s, &mut newton, outcome);
    s.newton = newton;
    met
}

/// What a Gauss–Seidel row update costs per particle of the strands it touches, over
/// what the factorization costs per unit of its work (Σ of its columns' counts
/// squared), each times how often it is done in a projection: about forty sweeps at
/// 1.5 ns a particle, about four factorizations at 0.7 ns a unit (a dropped pile and
/// a coiling rope, one thread, measured).
const SWEEPS_OVER_FACTORIZATIONS: f64 = 20.0;

/// Whether the sweeps over the rows' responses would cost less than the Newton steps'
/// factorizations: short strands in a dense pile, where each response is a few
/// particles long and the system's fill is not. Long strands are the other way: a
/// response is as long as its strand, a factor's column is not.
fn prefers_sweeps(responses: f64, work: f64) -> bool {
    work > SWEEPS_OVER_FACTORIZATIONS * responses
}

/// The particles of every row's responses: what a sweep over the rows writes.
fn responses(s: &ContactScratch) -> f64 {
    s.rows
        .iter()
        .flat_map(|row| &row.links[..row.link_count as usize])
        .map(|&(part, ..)| f64::from(s.parts[part as usize].particles.1))
        .sum()
}

/// The heaviest free particle over the lightest, among `inverse_mass` (1 when none).
fn mass_spread(inverse_mass: &[f64]) -> f64 {
    let (low, high) = (inverse_mass.iter())
        .filter(|&&w| w > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(low, high), &w| {
            (low.min(w), high.max(w))
        });
    if high > 0.0 { high / low } else { 1.0 }
}

/// A contact group whose free particles' masses spread wider than this is left to the
/// Newton under `Auto`: a crate on a rope two thousand times lighter measured 2 275
/// fail-safe steps in 3 000 by the sweeps at 1/600 s, 7 by the Newton; crates' frames
/// on a rope bridge (spread 8 to 67) kept rocking at millimetres a second by the
/// sweeps, which the Newton brings to rest.
const SWEPT_MASS_SPREAD: f64 = 4.0;

/// Responses shorter than this many particles on average are left to the sweeps
/// without weighing the factorization (whose analysis alone costs a few of their
/// sweeps): a pile's or a fur's strands, where the sweeps measured two to six times
/// faster.
const SHORT_RESPONSES: f64 = 48.0;

fn kkt_input<'a>(s: &'a ContactScratch, included: &'a [bool]) -> KktInput<'a> {
    KktInput {
        inverse_mass: &s.inverse_mass,
        included,
        ends: &s.ends,
        locked: &s.locked,
        incident: &s.incident,
        incident_start: &s.incident_start,
        rows: &s.rows,
    }
}

/// The Newton iterations over the rows and edges of `s` (see the module doc), or `None`
/// where `Auto` leaves them to the sweeps.
fn run(
    settings: &ContactSettings,
    s: &mut ContactScratch,
    w: &mut NewtonScratch,
    outcome: &mut ContactOutcome,
) -> Option<bool> {
    w.kkt.factorizations = 0;
    w.kkt.threads = s.threads;
    let links: usize = s.rows.iter().map(|row| row.link_count as usize).sum();
    let swept = responses(s);
    // Sweeps converge at the rate of the lightest particle against the heaviest; past
    // a spread of masses the Newton is the only one that gets there.
    let sweeps_can = mass_spread(&s.inverse_mass) < SWEPT_MASS_SPREAD;
    if settings.solver == ContactSolver::Auto
        && sweeps_can
        && swept < SHORT_RESPONSES * links as f64
    {
        return None;
    }
    set_up(s, w);
    if settings.solver == ContactSolver::Auto && sweeps_can && prefers_sweeps(swept, w.kkt.work()) {
        return None;
    }
    let tolerance = settings.contact_tolerance;
    let cap = settings.rows_give_way.max(1);
    let trust = 0.5 * s.shortest_edge();
    // Once the rows are met, the edges' polish moves particles by about the residual
    // times an edge: no more than the contact tolerance.
    let polish = (tolerance / (2.0 * trust)).clamp(ROUND_OFF_FLOOR, 1e-3);
    let mut last_violation = f64::INFINITY;
    let mut full_until = FULL_STEPS;
    let mut met = false;
    let mut best = (f64::INFINITY, 0);
    let mut renewed = false;
    for step in 0..cap {
        set_correction(s, &w.momentum);
        measure_edges(s);
        choose_model(s, w, step == 0, renewed);
        renewed = false;
        let Some((alpha, longest)) = newton_step(s, w, trust, step < full_until, outcome) else {
            break;
        };
        // A step whose part left untaken moves nothing that matters is taken whole.
        let whole = (1.0 - alpha) * longest <= 1e-3 * tolerance;
        let violation = coulomb_violation(s, w);
        let holds = whole && model_holds(s, w, tolerance);
        // Until the edges are nearly met, their next linearization moves the rows
        // more than a shift would: solve again before judging the rows.
        let settled = measure_edges(s) <= polish;
        // Met: no row farther from Coulomb's law than the tolerance, and none pulling by
        // more than would move it that far, whether or not the model's states hold.
        met = violation <= tolerance && pull_at_most(s, w, tolerance);
        if met && settled {
            break;
        }
        // Past the whole steps, rows whose states still change (a degenerate cluster)
        // but are within a few tolerances are as good as the sweeps left theirs: leave
        // them once the edges' polish moves no more than that.
        if step + 1 >= FULL_STEPS
            && !holds
            && violation <= CLOSE_ENOUGH * tolerance
            && measure_edges(s) <= stalled_polish(violation, tolerance, trust)
        {
            break;
        }
        if !(holds && settled) {
            // Rows that stop improving (a degenerate cluster trading impulses between
            // cone edges that are combinations of each other) are left where they are
            // once the edges are within what they fall short, as the sweeps' rows
            // were: the polish then moves particles by no more than that.
            if violation < 0.5 * best.0 {
                best = (violation, step);
            } else if step >= best.1 + STALL
                && measure_edges(s) <= stalled_polish(violation, tolerance, trust)
            {
                break;
            }
            continue;
        }
        if met {
            continue;
        }
        // The rows' give is over the tolerance (a heavy load on a light row): shift
        // each row by its impulse and solve again. Rows that cannot all be met stall.
        if violation > 0.5 * last_violation {
            break;
        }
        last_violation = violation;
        renew_shifts(s, w);
        full_until = step + 1 + FULL_STEPS;
        renewed = true;
    }
    finish(s, w, outcome);
    Some(met)
}

/// How far the edges' polish may leave them when rows that stall are left as they are:
/// about the residual times an edge (`2 trust`) moves particles no more than the rows
/// fall short.
fn stalled_polish(violation: f64, tolerance: f64, trust: f64) -> f64 {
    (violation.max(tolerance) / (2.0 * trust)).min(1e-3)
}

/// The rows' stiffness and shifts (the warm start), the iterate's buffers, and the
/// system's pattern numbered once for the projection.
fn set_up(s: &ContactScratch, w: &mut NewtonScratch) {
    let (n, rows) = (s.packed.len(), s.rows.len());
    w.stiffness.clear();
    w.shift.clear();
    for row in &s.rows {
        let own: f64 = row.entries[..row.count as usize]
            .iter()
            .map(|&(j, c)| c * c * s.inverse_mass[j as usize])
            .sum();
        let k = if own > 0.0 { STIFFNESS / own } else { 0.0 };
        w.stiffness.push(k);
        // The warm start is the shift: the first problem already asks each row for last
        // step's impulses where it is met. Applying them as impulses instead would move
        // their particles alone, as far as they stop whole strands.
        let lambda = warm_lambda(row);
        w.shift.push(if k > 0.0 {
            [lambda[0] / k, lambda[1] / k]
        } else {
            [0.0; 2]
        });
    }
    w.model.clear();
    w.model.resize(rows, RowModel::default());
    w.lift.clear();
    w.lift.resize(rows, 0.0);
    w.pressed.clear();
    w.pressed.resize(rows, [false; 2]);
    w.lambda.clear();
    w.lambda.resize(rows, [0.0; 2]);
    w.momentum.clear();
    w.momentum.resize(n, DVec2::ZERO);
    w.tension.clear();
    w.tension.resize(s.ends.len(), 0.0);
    w.ahead.clear();
    // The system's pattern holds every row: rows met at first and pressed later would
    // otherwise each ask for the pattern to be analysed again, which cost more than
    // the fill they save (a coiling rope: 7.1 s against 4.6 s).
    w.included.clear();
    w.included.extend(w.stiffness.iter().map(|&k| k > 0.0));
    w.kkt.number(&kkt_input(s, &w.included));
}

/// One Newton step from the iterate in `w`: factor the system at the current edges,
/// solve for the full step and for the edges alone, and move along the line between
/// them (whole, `whole`, or to the line search's minimum), no edge's span changing by
/// more than `trust`. Returns the step taken (`alpha`) and the longest particle move
/// of the full step, or `None` where the factorization failed.
fn newton_step(
    s: &mut ContactScratch,
    w: &mut NewtonScratch,
    trust: f64,
    whole: bool,
    outcome: &mut ContactOutcome,
) -> Option<(f64, f64)> {
    let n = s.packed.len();
    let rows = s.rows.len();
    let unknowns = w.kkt.unknowns();
    // Taut edges' curvature (tension over length) makes the steps Newton's on the
    // manifold the edges allow, not on its tangent plane; slack ones are left out,
    // so the system stays quasi-definite.
    w.curvature.clear();
    (w.curvature).extend(
        w.tension
            .iter()
            .zip(&s.edge)
            .map(|(&t, d)| t.max(0.0) / d.length()),
    );
    if (w.kkt)
        .assemble_and_factor(&kkt_input(s, &w.included), &w.model, &s.edge, &w.curvature)
        .is_err()
    {
        return None;
    }
    outcome.iterations += 1;
    w.whole = whole;
    right_hand_sides(s, w, unknowns);
    w.kkt.solve(&mut w.full);
    w.kkt.solve(&mut w.feasible);
    lines(s, w);
    // The line: its start (the edges met) and the way to the full step's end.
    set_correction(s, &w.start);
    let mut mass = (0.0, 0.0);
    let mut longest = 0.0f64;
    for j in 0..n {
        let b = s.inverse_mass[j] * w.step[j];
        mass.0 += w.start[j].dot(b);
        mass.1 += w.step[j].dot(b);
        longest = longest.max(b.length());
    }
    // The trust region bounds how the edges' spans change (see `within_trust`).
    let swing = longest_swing(&s.ends, |j| s.inverse_mass[j] * w.step[j]);
    shifted_values(s, w);
    set_correction(s, &w.step);
    w.slope.clear();
    for row in &s.rows {
        let (a, b) = row_motion(row, &s.correction);
        let e = cone(row.friction);
        w.slope.push(e.map(|e| e.0 * a + e.1 * b));
    }
    let high = within_trust(swing, trust);
    let line = Line {
        rows: &s.rows,
        stiffness: &w.stiffness,
        value: &w.value,
        slope: &w.slope,
        mass,
    };
    // Whole steps first, so that the rows' states follow the iterate several at
    // once; then a line search, which may stop at the first stiff row a step
    // presses but never goes uphill.
    let alpha = if w.whole { high } else { line.minimize(high) };
    w.ahead.clear();
    if alpha < 1.0 {
        let ahead = w.value.iter().zip(&w.slope);
        w.ahead
            .extend(ahead.map(|(v, d)| [v[0] + d[0], v[1] + d[1]]));
    }
    for j in 0..n {
        w.momentum[j] = w.start[j] + alpha * w.step[j];
    }
    for r in 0..rows {
        for e in 0..2 {
            w.lambda[r][e] = w.start_lambda[r][e] + alpha * w.step_lambda[r][e];
        }
    }
    for k in 0..s.ends.len() {
        w.tension[k] = w.start_tension[k] + alpha * w.step_tension[k];
    }
    set_correction(s, &w.momentum);
    Some((alpha, longest))
}

/// Renew the rows' shifts at their impulses, and lift each sliding row by what the
/// cone asked of it.
fn renew_shifts(s: &ContactScratch, w: &mut NewtonScratch) {
    // A sliding row is lifted by what the cone asked of it, μ |u_t| (Tasora and
    // Anitescu's fixed point): solved again, it slides on its target, not above.
    for (r, row) in s.rows.iter().enumerate() {
        let [a, b] = w.pressed[r];
        w.lift[r] = if a != b {
            row.friction * row_values(row, &s.correction).1.abs()
        } else {
            0.0
        };
    }
    for (r, shift) in w.shift.iter_mut().enumerate() {
        let k = w.stiffness[r];
        if k > 0.0 {
            *shift = w.lambda[r].map(|l| l.max(0.0) / k);
        }
    }
}

/// The result: each row's impulses, the edges' tensions added to their impulses.
fn finish(s: &mut ContactScratch, w: &NewtonScratch, outcome: &mut ContactOutcome) {
    // Each row's impulses; a cone edge the last step left pulling keeps it (it is in
    // Δ), but carries none into the next step's warm start.
    for (row, lambda) in s.rows.iter_mut().zip(&w.lambda) {
        (row.mu_n, row.mu_t) = impulse(row.friction, lambda.map(|l| l.max(0.0)));
    }
    for (impulse, tension) in s.edge_impulse.iter_mut().zip(&w.tension) {
        *impulse += tension;
    }
    outcome.factorizations += w.kkt.factorizations;
}

/// A row's warm cone impulses from its (normal, tangent) warm start, inside the cone.
fn warm_lambda(row: &LocalRow) -> [f64; 2] {
    let normal = row.mu_n.max(0.0);
    if row.friction <= 0.0 {
        return [normal, 0.0];
    }
    let s = (1.0 + row.friction * row.friction).sqrt();
    let along = (row.mu_t / row.friction).clamp(-normal, normal);
    [0.5 * s * (normal + along), 0.5 * s * (normal - along)]
}

/// The model at the iterate: which cone edges of each row press. An edge presses if it
/// is short at the iterate, or at the end of the last step where the line search
/// stopped before it (the step would have pressed it), or if the model pressed it and
/// it still pushes without being clear (the model leaves it at −λ/k, zero where λ is);
/// on the first step, every edge with a warm impulse.
fn choose_model(s: &ContactScratch, w: &mut NewtonScratch, first: bool, renewed: bool) {
    w.value.clear();
    for (r, row) in s.rows.iter().enumerate() {
        let k = w.stiffness[r];
        let values = cone_values(row, r, w, &s.correction);
        let e = cone(row.friction);
        let mut model = RowModel::default();
        let mut value = [0.0; 2];
        let mut pressed = [false; 2];
        for x in 0..edges(row.friction) {
            let u = values[x];
            value[x] = u;
            if k == 0.0 {
                continue;
            }
            let ahead = w.ahead.get(r).is_some_and(|a| a[x] < 0.0);
            // A primal–dual active set's rule: an edge stays pressed while its impulse
            // outweighs how far it is clear, λ − k u > 0, so an edge the edges'
            // curvature lifts a little off its target keeps what holds it.
            let held = if first {
                k * w.shift[r][x]
            } else {
                w.lambda[r][x]
            };
            // Just after the shifts and lifts are renewed, every pushing edge stays: a
            // lift moves its target by more than its give, λ/k, and a pressed edge
            // would otherwise seem clear and be dropped for a step.
            let kept = held > 0.0 && (renewed || held - k * u > 0.0);
            if u < 0.0 || ahead || kept {
                pressed[x] = true;
                model.nn += k * e[x].0 * e[x].0;
                model.nt += k * e[x].0 * e[x].1;
                model.tt += k * e[x].1 * e[x].1;
            }
        }
        w.model[r] = model;
        w.pressed[r] = pressed;
        w.value.push(value);
    }
}

/// The rows' shifted cone values at the current corrections, into `w.value`.
fn shifted_values(s: &ContactScratch, w: &mut NewtonScratch) {
    w.value.clear();
    for (r, row) in s.rows.iter().enumerate() {
        let values = cone_values(row, r, w, &s.correction);
        w.value.push(values);
    }
}

/// The right-hand sides: the full step (the objective's forces at the iterate) and
/// the step that only meets the edges.
fn right_hand_sides(s: &ContactScratch, w: &mut NewtonScratch, unknowns: usize) {
    w.full.clear();
    w.full.resize(unknowns, 0.0);
    w.feasible.clear();
    w.feasible.resize(unknowns, 0.0);
    for (j, p) in w.momentum.iter().enumerate() {
        let u = w.kkt.particle_unknown[j];
        if u != NONE {
            w.full[u as usize] = -p.x;
            w.full[u as usize + 1] = -p.y;
        }
    }
    for (r, row) in s.rows.iter().enumerate() {
        let force = impulse(row.friction, [0, 1].map(|x| edge_force(w, r, x)));
        if force == (0.0, 0.0) {
            continue;
        }
        let direction = force.0 * row.normal + force.1 * row.normal.perp();
        for &(j, c) in &row.entries[..row.count as usize] {
            let u = w.kkt.particle_unknown[j as usize];
            if u != NONE {
                w.full[u as usize] += c * direction.x;
                w.full[u as usize + 1] += c * direction.y;
            }
        }
    }
    for (k, &e) in w.kkt.edge_unknown.iter().enumerate() {
        if e != NONE {
            let rhs = -s.constraint[k] / (2.0 * s.edge[k].length());
            w.full[e as usize] = rhs;
            w.feasible[e as usize] = rhs;
        }
    }
}

/// Cone edge `x` of row `r`'s impulse in this step's model at its shifted value. In
/// whole steps, a primal–dual active set's: the model's linear force on a pressed
/// edge, pulling if the edge is clear (its target is where the model holds it). With
/// the line search, minus the objective's gradient, whatever the model presses (the
/// model then only chooses the Hessian, so every step goes downhill).
fn edge_force(w: &NewtonScratch, r: usize, x: usize) -> f64 {
    let (k, u) = (w.stiffness[r], w.value[r][x]);
    if w.whole && w.pressed[r][x] {
        -k * u
    } else {
        k * (-u).max(0.0)
    }
}

/// The line of this Newton step: its start (the step that meets the edges taken, the
/// rows' impulses as the model moves them there) in `w.start`, and the way from there
/// to the full step's end in `w.step`, as particle impulses, cone impulses and edge
/// tensions, each a sum of equal and opposite impulses.
fn lines(s: &ContactScratch, w: &mut NewtonScratch) {
    let n = s.packed.len();
    w.start.clear();
    w.start.extend_from_slice(&w.momentum);
    w.step.clear();
    w.step.resize(n, DVec2::ZERO);
    w.start_lambda.clear();
    w.step_lambda.clear();
    for (r, row) in s.rows.iter().enumerate() {
        let k = w.stiffness[r];
        let e = cone(row.friction);
        let (dn_f, dt_f) = unknown_motion(row, &w.kkt.particle_unknown, &w.feasible);
        let (dn, dt) = unknown_motion(row, &w.kkt.particle_unknown, &w.full);
        let (mut start, mut end) = ([0.0; 2], [0.0; 2]);
        for x in 0..edges(row.friction) {
            let force = edge_force(w, r, x);
            let held = if k > 0.0 && w.pressed[r][x] { k } else { 0.0 };
            start[x] = w.lambda[r][x] - held * (e[x].0 * dn_f + e[x].1 * dt_f);
            end[x] = force - held * (e[x].0 * dn + e[x].1 * dt);
        }
        let (now, first) = (
            impulse(row.friction, w.lambda[r]),
            impulse(row.friction, start),
        );
        push(row, (first.0 - now.0, first.1 - now.1), &mut w.start);
        push(row, impulse(row.friction, end), &mut w.step);
        w.start_lambda.push(start);
        w.step_lambda.push([end[0] - start[0], end[1] - start[1]]);
    }
    w.start_tension.clear();
    w.step_tension.clear();
    for (k, &(a, b)) in s.ends.iter().enumerate() {
        let e = w.kkt.edge_unknown[k];
        let (feasible, full) = if e == NONE {
            (0.0, 0.0)
        } else {
            (w.feasible[e as usize], w.full[e as usize])
        };
        // The edges' multipliers λ enter as −Jᵀλ: a tension λ pulling a to b; their
        // curvature as −G δ, equal and opposite on the ends.
        let d = s.edge[k].normalize_or_zero();
        pull(a, b, d, feasible, &mut w.start);
        pull(a, b, d, full, &mut w.step);
        let c = w.curvature[k];
        if c > 0.0 {
            let motion = |x: &[f64]| -> DVec2 {
                let at = |j: u32| unknown_vector(&w.kkt.particle_unknown, x, j);
                at(b) - at(a)
            };
            pull(a, b, c * motion(&w.feasible), 1.0, &mut w.start);
            pull(a, b, c * motion(&w.full), 1.0, &mut w.step);
        }
        let start = w.tension[k] + feasible;
        w.start_tension.push(start);
        w.step_tension.push(full - start);
    }
    // `step` held the full step's end: make it the way there.
    for (step, start) in w.step.iter_mut().zip(&w.start) {
        *step -= *start;
    }
}

/// Whether the rows at the iterate are as the model held them: pressed cone edges
/// still pushing, the others clear (within a thousandth of the tolerance, so that an
/// edge at the border of both may be taken for either).
fn model_holds(s: &ContactScratch, w: &NewtonScratch, tolerance: f64) -> bool {
    let slack = 1e-3 * tolerance;
    s.rows.iter().enumerate().all(|(r, row)| {
        let k = w.stiffness[r];
        if k == 0.0 {
            return true;
        }
        let values = cone_values(row, r, w, &s.correction);
        // An impulse's slack is what moves the row's own mass by the slack.
        let own = k / STIFFNESS;
        (0..edges(row.friction)).all(|x| {
            if w.pressed[r][x] {
                w.lambda[r][x] >= -own * slack
            } else {
                values[x] >= -slack
            }
        })
    })
}

/// Whether no cone edge pulls by more than an impulse that moves its row's own mass by
/// `distance`.
fn pull_at_most(s: &ContactScratch, w: &NewtonScratch, distance: f64) -> bool {
    (0..s.rows.len()).all(|r| {
        let own = w.stiffness[r] / STIFFNESS;
        w.lambda[r].iter().all(|&l| l >= -own * distance)
    })
}

/// How far (a distance per step) the rows are from Coulomb's law at the iterate: a row
/// short of its target, a pressed one clear of it (the convex cone lifts a sliding
/// contact by μ times its sliding), a sticking one sliding.
fn coulomb_violation(s: &ContactScratch, w: &NewtonScratch) -> f64 {
    let mut worst = 0.0f64;
    for (r, row) in s.rows.iter().enumerate() {
        if w.stiffness[r] == 0.0 {
            continue;
        }
        let (un, ut) = row_values(row, &s.correction);
        let [a, b] = w.pressed[r];
        worst = worst.max(-un);
        if a || b {
            worst = worst.max(un);
        }
        if a && b {
            worst = worst.max(ut.abs());
        }
    }
    worst
}

/// `s.correction = W p` (fixed particles stay).
fn set_correction(s: &mut ContactScratch, p: &[DVec2]) {
    for ((c, &w), p) in s.correction.iter_mut().zip(&s.inverse_mass).zip(p) {
        *c = w * *p;
    }
}
