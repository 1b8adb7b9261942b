//! Fast projection of an island onto its length constraints, optionally subject to
//! contacts that must not approach (DESIGN §5, §7). A path or a loop has a tridiagonal
//! system (Thomas; Sherman–Morrison for the loop's corners); a tree or a general graph
//! a sparse one, factored by [`super::sparse`] in the order its layout planned.
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
//! **Contacts.** After collision impulses, an island is projected again with each of
//! its contacts as an inequality row `Σ cᵢ n·vᵢ ≥ target` (a point against an edge:
//! the point's velocity minus the edge's at the contact point, along the normal).
//! Each Newton step eliminates the edge unknowns through the island's factor (one
//! solve per contact column), leaving a small contact-space complementarity problem,
//! solved by projected Gauss–Seidel. The edge equations hold exactly for any contact
//! impulses, so lengths are exact whatever the contacts do; the contacts are met to
//! the complementarity tolerance. Particles outside the island keep their velocities.
//! With contacts the end-of-step direction is used, whatever the setting, since the
//! elimination needs the symmetric system.
//!
//! A pure kernel: slices in, slices out, no allocation once the scratch is sized.

use bevy::math::DVec2;
use bevy::prelude::Reflect;

use super::cyclic::CyclicFactor;
use super::graph::GraphLayout;
use super::islands::IslandEdge;
use super::sparse::SparseFactor;
use super::tridiagonal::{SingularPivot, TridiagonalFactor, solve_tridiagonal};

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
    /// How far (a distance per step) a contact row may fall short of its target.
    pub contact_tolerance: f64,
    /// Reject the projection (change nothing) if it would move any particle by more
    /// than this fraction of the island's shortest rest length in one step; infinite
    /// for no limit. Guards re-projections under contact, where nearly dependent
    /// constraints can ask for absurd corrections.
    pub max_correction: f64,
}

/// How a projection ended.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProjectionOutcome {
    /// Linear solves performed.
    pub iterations: u32,
    /// Whether the edge tolerance was met. Contacts are met to their tolerance or as
    /// well as the complementarity solve could: see `contact_violation`.
    pub converged: bool,
    /// Final `max |C_k| / L_k²`.
    pub residual: f64,
    /// Final largest contact violation: how far (in distance per step) a contact row
    /// falls short of its target.
    pub contact_violation: f64,
    /// Whether a linear solve met a singular system; the velocities are then left as
    /// the last good iterate gives them.
    pub singular: bool,
    /// Edges of zero length, left as they are (they have no direction to act along).
    pub locked: u32,
    /// Whether the corrections exceeded `max_correction` and were not applied.
    pub rejected: bool,
}

/// A contact that the projection must not make approach: `Σ cᵢ n·vᵢ ≥ target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactRow {
    /// The particles involved (packed indices).
    pub particles: [u32; 3],
    /// Their coefficients.
    pub coefficients: [f64; 3],
    /// The contact normal.
    pub normal: DVec2,
    /// The smallest allowed `Σ cᵢ n·vᵢ`.
    pub target: f64,
}

impl ContactRow {
    /// Point p against edge (q, r) at `(1 − α) q + α r`, along `normal`, with the
    /// current relative normal velocity as the target.
    pub fn point_edge(
        p: u32,
        q: u32,
        r: u32,
        alpha: f64,
        normal: DVec2,
        velocity: &[DVec2],
    ) -> ContactRow {
        let mut row = ContactRow {
            particles: [p, q, r],
            coefficients: [1.0, alpha - 1.0, -alpha],
            normal,
            target: 0.0,
        };
        row.target = row.normal_velocity(velocity);
        row
    }

    /// `Σ cᵢ n·vᵢ` for these velocities.
    pub fn normal_velocity(&self, velocity: &[DVec2]) -> f64 {
        self.particles
            .iter()
            .zip(self.coefficients)
            .map(|(&p, c)| c * self.normal.dot(velocity[p as usize]))
            .sum()
    }
}

/// Edge residual (`|C| / L²`) below which the contacts may be settled and the edges
/// polished alone: the remaining corrections are then a millionth of an edge, too small
/// to disturb a contact.
const POLISH_RESIDUAL: f64 = 1e-6;

/// Contact rows one projection takes at most; further ones are left to the collision
/// stage's verification.
pub const MAX_CONTACT_ROWS: usize = 64;

/// A contact row in island-local terms.
#[derive(Clone, Copy, Debug, Default)]
struct LocalRow {
    entries: [(u32, f64); 3],
    count: usize,
    normal: DVec2,
    /// Current `Σ cᵢ n·vᵢ − target`, times dt (a distance per step).
    slack: f64,
}

/// Reusable buffers for [`project_island`], sized by [`IslandScratch::reserve`].
#[derive(Clone, Debug, Default)]
pub struct IslandScratch {
    correction: Vec<DVec2>,
    inverse_mass: Vec<f64>,
    locked: Vec<bool>,
    predicted_edge: Vec<DVec2>,
    edge: Vec<DVec2>,
    start_direction: Vec<DVec2>,
    constraint: Vec<f64>,
    lower: Vec<f64>,
    diagonal: Vec<f64>,
    upper: Vec<f64>,
    rhs: Vec<f64>,
    thomas: Vec<f64>,
    factors: Factors,
    local_of: Vec<u32>,
    rows: Vec<LocalRow>,
    columns: Vec<std::ops::Range<u32>>,
    column_entries: Vec<(u32, f64)>,
    solved_columns: Vec<f64>,
    schur: Vec<f64>,
    offset: Vec<f64>,
    impulse: Vec<f64>,
    contact_residual: Vec<f64>,
    row_particles: Vec<(u32, u32, f64)>,
}

impl IslandScratch {
    /// Make room for islands of up to `edges` edges among `particles` particles
    /// (allocates only when growing).
    pub fn reserve(&mut self, edges: usize, particles: usize) {
        grow(&mut self.correction, particles, DVec2::ZERO);
        grow(&mut self.inverse_mass, particles, 0.0);
        grow(&mut self.locked, edges, false);
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
    }

    /// Make room for contact rows on islands of up to `edges` edges, at most `degree`
    /// of them at a particle, among `particles` packed particles.
    pub fn reserve_contacts(&mut self, edges: usize, degree: usize, particles: usize) {
        grow(&mut self.local_of, particles, NOT_IN_CHAIN);
        let rows = MAX_CONTACT_ROWS;
        self.rows.reserve(rows.saturating_sub(self.rows.len()));
        grow(&mut self.columns, rows, 0..0);
        grow(&mut self.solved_columns, rows * edges, 0.0);
        grow(&mut self.schur, rows * rows, 0.0);
        grow(&mut self.offset, rows, 0.0);
        grow(&mut self.impulse, rows, 0.0);
        grow(&mut self.contact_residual, rows, 0.0);
        self.row_particles
            .reserve((3 * rows).saturating_sub(self.row_particles.len()));
        // Up to `degree` edges at each of a row's three particles.
        self.column_entries
            .reserve((3 * degree * rows).saturating_sub(self.column_entries.len()));
    }
}

const NOT_IN_CHAIN: u32 = u32::MAX;

fn grow<T: Clone>(buffer: &mut Vec<T>, n: usize, value: T) {
    if buffer.len() < n {
        buffer.resize(n, value);
    }
}

/// The smallest `|C| / L²` asked for whatever the tolerance: edges are formed from
/// coordinate differences, so f64 resolves them to a few ulps of their own length and
/// asking for less would only spin.
pub const ROUND_OFF_FLOOR: f64 = 16.0 * f64::EPSILON;

/// The particle slices a projection reads and writes.
#[derive(Debug)]
pub struct Bodies<'a> {
    /// Positions at the start of the step.
    pub position: &'a [DVec2],
    /// Predictor velocities in, projected velocities out.
    pub velocity: &'a mut [DVec2],
    /// Inverse masses (0: pinned, or held fixed).
    pub inverse_mass: &'a [f64],
}

/// A path or loop island: its edges in walking order (edge k + 1 starts where edge k
/// ends; when `closed`, the last ends where the first starts).
#[derive(Clone, Copy, Debug)]
pub struct Chain<'a> {
    /// The edges, in order.
    pub edges: &'a [IslandEdge],
    /// Whether the chain is a loop.
    pub closed: bool,
}

/// A tree or graph island: its edges in the layout's order, and the layout.
#[derive(Clone, Copy, Debug)]
pub struct Graph<'a> {
    /// The edges, in [`GraphLayout`] order.
    pub edges: &'a [IslandEdge],
    /// Local particles, incidence and the sparse plan.
    pub layout: &'a GraphLayout,
}

/// Any island the projection solves.
#[derive(Clone, Copy, Debug)]
pub enum IslandView<'a> {
    /// A path or a loop: a tridiagonal or cyclic tridiagonal system.
    Chain(Chain<'a>),
    /// A tree or graph: a sparse LDLᵀ.
    Graph(Graph<'a>),
}

/// How the projection walks an island's particles and edges, and solves its system:
/// a generic parameter, so that each kind's loops compile without a branch per edge.
trait Walk: Copy {
    /// Particles of the island of `edges`.
    fn particles(self, edges: &[IslandEdge]) -> usize;
    /// Packed index of local particle `j`.
    fn particle(self, edges: &[IslandEdge], j: usize) -> usize;
    /// Local ends of edge `k`.
    fn ends(self, k: usize, particles: usize) -> (usize, usize);
    /// The island edges at local particle `j`, with −1 where `j` starts the edge and +1
    /// where it ends it.
    fn for_incident(self, j: usize, m: usize, visit: impl FnMut(usize, f64));
    /// The most island edges at one particle.
    fn max_degree(self) -> usize;
    /// Whether the system must be the symmetric (end-of-step) one.
    fn symmetric_only(self) -> bool;
    /// Assemble and factor the system at the current iterate, and solve it for
    /// `s.rhs`; keep the factor for [`Walk::solve_many`] when `keep_factor`.
    fn solve(
        self,
        m: usize,
        direction: ConstraintDirection,
        keep_factor: bool,
        s: &mut IslandScratch,
    ) -> Result<(), SingularPivot>;
    /// Solve again with the kept factor, for `k` right-hand sides row by row.
    fn solve_many(self, m: usize, factors: &Factors, columns: &mut [f64], k: usize);
}

/// A path or a loop.
#[derive(Clone, Copy, Debug)]
struct ChainWalk {
    closed: bool,
}

impl Walk for ChainWalk {
    fn particles(self, edges: &[IslandEdge]) -> usize {
        edges.len() + usize::from(!self.closed)
    }

    #[inline]
    fn particle(self, edges: &[IslandEdge], j: usize) -> usize {
        (if j < edges.len() {
            edges[j].a
        } else {
            edges[j - 1].b
        }) as usize
    }

    #[inline]
    fn ends(self, k: usize, particles: usize) -> (usize, usize) {
        (k, if k + 1 == particles { 0 } else { k + 1 })
    }

    fn for_incident(self, j: usize, m: usize, mut visit: impl FnMut(usize, f64)) {
        if j < m {
            visit(j, -1.0);
        }
        if j > 0 {
            visit(j - 1, 1.0);
        } else if self.closed {
            visit(m - 1, 1.0);
        }
    }

    fn max_degree(self) -> usize {
        2
    }

    fn symmetric_only(self) -> bool {
        false
    }

    fn solve(
        self,
        m: usize,
        direction: ConstraintDirection,
        keep_factor: bool,
        s: &mut IslandScratch,
    ) -> Result<(), SingularPivot> {
        chain_solve(m, self.closed, direction, keep_factor, s)
    }

    fn solve_many(self, m: usize, factors: &Factors, columns: &mut [f64], k: usize) {
        if self.closed && m >= 3 {
            factors.cyclic.solve_many(columns, k);
        } else {
            factors.open.solve_many(columns, k);
        }
    }
}

/// A tree or a graph.
#[derive(Clone, Copy, Debug)]
struct GraphWalk<'a> {
    layout: &'a GraphLayout,
}

impl Walk for GraphWalk<'_> {
    fn particles(self, _edges: &[IslandEdge]) -> usize {
        self.layout.particles.len()
    }

    #[inline]
    fn particle(self, _edges: &[IslandEdge], j: usize) -> usize {
        self.layout.particles[j] as usize
    }

    #[inline]
    fn ends(self, k: usize, _particles: usize) -> (usize, usize) {
        let (a, b) = self.layout.ends[k];
        (a as usize, b as usize)
    }

    fn for_incident(self, j: usize, _m: usize, mut visit: impl FnMut(usize, f64)) {
        for &(k, sign) in self.layout.incident(j) {
            visit(k as usize, sign);
        }
    }

    fn max_degree(self) -> usize {
        self.layout.max_degree
    }

    fn symmetric_only(self) -> bool {
        true
    }

    fn solve(
        self,
        m: usize,
        _direction: ConstraintDirection,
        _keep_factor: bool,
        s: &mut IslandScratch,
    ) -> Result<(), SingularPivot> {
        graph_solve(m, self.layout, s)
    }

    fn solve_many(self, _m: usize, factors: &Factors, columns: &mut [f64], k: usize) {
        factors.sparse.solve_many(&self.layout.plan, columns, k);
    }
}

/// The factors an island's system may be kept in between solves.
#[derive(Clone, Debug, Default)]
struct Factors {
    open: TridiagonalFactor,
    cyclic: CyclicFactor,
    sparse: SparseFactor,
}

/// Project the velocities of one chain so that every edge ends the step at its rest
/// length, and no contact row falls below its target; see [`project_island`].
pub fn project_chain(
    chain: Chain,
    bodies: Bodies,
    contacts: &[ContactRow],
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    project_island(
        IslandView::Chain(chain),
        bodies,
        contacts,
        dt,
        settings,
        scratch,
    )
}

/// Project the velocities of one island so that every edge ends the step at its rest
/// length, and no contact row falls below its target. Only free particles of the
/// island change velocity. Returns how the iteration ended; on a singular system the
/// corrections found so far are applied. Trees and graphs always use the end-of-step
/// direction: their sparse factorization needs the symmetric system.
pub fn project_island(
    island: IslandView,
    bodies: Bodies,
    contacts: &[ContactRow],
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    match island {
        IslandView::Chain(Chain { edges, closed }) => project_walk(
            edges,
            ChainWalk { closed },
            bodies,
            contacts,
            dt,
            settings,
            scratch,
        ),
        IslandView::Graph(Graph { edges, layout }) => project_walk(
            edges,
            GraphWalk { layout },
            bodies,
            contacts,
            dt,
            settings,
            scratch,
        ),
    }
}

fn project_walk<W: Walk>(
    edges: &[IslandEdge],
    walk: W,
    bodies: Bodies,
    contacts: &[ContactRow],
    dt: f64,
    settings: &ProjectionSettings,
    scratch: &mut IslandScratch,
) -> ProjectionOutcome {
    let Bodies {
        position,
        velocity,
        inverse_mass,
    } = bodies;
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
    if !contacts.is_empty() {
        scratch.reserve_contacts(m, walk.max_degree(), velocity.len());
    }
    localize_contacts(contacts, particles, &particle, velocity, dt, scratch);
    let direction = if scratch.rows.is_empty() && !walk.symmetric_only() {
        settings.direction
    } else {
        ConstraintDirection::EndOfStep
    };

    let mut outcome = ProjectionOutcome {
        locked: scratch.locked[..m].iter().filter(|&&l| l).count() as u32,
        ..Default::default()
    };
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
        if newton_step(m, particles, walk, direction, contact_tolerance, s).is_err() {
            outcome.singular = true;
            break;
        }
    }

    let correction = &scratch.correction[..particles];
    if settings.max_correction.is_finite() {
        let limit = settings.max_correction * shortest;
        if correction
            .iter()
            .any(|c| c.length().is_nan() || c.length() > limit)
        {
            outcome.rejected = true;
            outcome.converged = false;
            return outcome;
        }
    }
    for (j, c) in correction.iter().enumerate() {
        if scratch.inverse_mass[j] > 0.0 {
            velocity[particle(j)] += *c / dt;
        }
    }
    outcome
}

/// Translate the contact rows touching the island into local rows (up to
/// [`MAX_CONTACT_ROWS`]), with their current slack.
fn localize_contacts(
    contacts: &[ContactRow],
    particles: usize,
    particle: &impl Fn(usize) -> usize,
    velocity: &[DVec2],
    dt: f64,
    scratch: &mut IslandScratch,
) {
    scratch.rows.clear();
    if contacts.is_empty() {
        return;
    }
    for j in 0..particles {
        scratch.local_of[particle(j)] = j as u32;
    }
    for row in contacts {
        let mut local = LocalRow {
            normal: row.normal,
            slack: (row.normal_velocity(velocity) - row.target) * dt,
            ..Default::default()
        };
        for (&p, &c) in row.particles.iter().zip(&row.coefficients) {
            let j = scratch.local_of[p as usize];
            if j != NOT_IN_CHAIN && scratch.inverse_mass[j as usize] > 0.0 && c != 0.0 {
                local.entries[local.count] = (j, c);
                local.count += 1;
            }
        }
        if local.count > 0 && scratch.rows.len() < MAX_CONTACT_ROWS {
            scratch.rows.push(local);
        }
    }
    // Which rows meet at which particle, for the N W Nᵀ terms.
    scratch.row_particles.clear();
    for (c, row) in scratch.rows.iter().enumerate() {
        for &(j, coefficient) in &row.entries[..row.count] {
            scratch.row_particles.push((j, c as u32, coefficient));
        }
    }
    scratch
        .row_particles
        .sort_unstable_by_key(|&(j, c, _)| (j, c));
    for j in 0..particles {
        scratch.local_of[particle(j)] = NOT_IN_CHAIN;
    }
}

/// How far the most violated row falls short, given the corrections so far.
fn contact_violation(rows: &[LocalRow], correction: &[DVec2]) -> f64 {
    rows.iter()
        .map(|row| -(row.slack + row_change(row, correction)))
        .fold(0.0, f64::max)
}

/// `Σ cᵢ n·Δᵢ` of a row for per-particle corrections Δ.
fn row_change(row: &LocalRow, correction: &[DVec2]) -> f64 {
    row.entries[..row.count]
        .iter()
        .map(|&(j, c)| c * row.normal.dot(correction[j as usize]))
        .sum()
}

/// One Newton step on the edges (and contact rows) from the current corrections.
fn newton_step<W: Walk>(
    m: usize,
    particles: usize,
    walk: W,
    direction_kind: ConstraintDirection,
    contact_tolerance: f64,
    s: &mut IslandScratch,
) -> Result<(), SingularPivot> {
    let rows = s.rows.len();
    for k in 0..m {
        s.rhs[k] = if s.locked[k] { 0.0 } else { -s.constraint[k] };
    }
    walk.solve(m, direction_kind, rows > 0, s)?;

    if rows > 0 {
        // Columns b_c = J W N_cᵀ, then Y = A⁻¹ B, all columns at once (row-major).
        let solved = &mut s.solved_columns[..m * rows];
        solved.fill(0.0);
        s.column_entries.clear();
        for c in 0..rows {
            let row = s.rows[c];
            let start = s.column_entries.len();
            for &(j, coefficient) in &row.entries[..row.count] {
                let j = j as usize;
                let pushed = s.inverse_mass[j] * coefficient * row.normal;
                let (edge, locked, entries) = (&s.edge, &s.locked, &mut s.column_entries);
                walk.for_incident(j, m, |k, sign| {
                    if locked[k] {
                        return;
                    }
                    let value = sign * 2.0 * edge[k].dot(pushed);
                    match entries[start..].iter_mut().find(|(i, _)| *i as usize == k) {
                        Some(entry) => entry.1 += value,
                        None => entries.push((k as u32, value)),
                    }
                });
            }
            for &(k, value) in &s.column_entries[start..] {
                solved[k as usize * rows + c] = value;
            }
            s.columns[c] = start as u32..s.column_entries.len() as u32;
        }
        walk.solve_many(m, &s.factors, solved, rows);
        // The contact-space system S μ + q ≥ 0, μ ≥ 0, complementary:
        // S = N W Nᵀ − Bᵀ A⁻¹ B, q = slack + Bᵀ λ.
        for c in 0..rows {
            let column = &s.column_entries[s.columns[c].start as usize..s.columns[c].end as usize];
            s.offset[c] = s.rows[c].slack
                + row_change(&s.rows[c], &s.correction)
                + column
                    .iter()
                    .map(|&(k, v)| v * s.rhs[k as usize])
                    .sum::<f64>();
            let schur_row = &mut s.schur[c * rows..(c + 1) * rows];
            schur_row.fill(0.0);
            for &(k, v) in column {
                let solved_row = &solved[k as usize * rows..(k as usize + 1) * rows];
                for (entry, y) in schur_row.iter_mut().zip(solved_row) {
                    *entry -= v * y;
                }
            }
        }
        // N W Nᵀ: only rows that share a particle meet.
        let w = &s.inverse_mass;
        for group in s.row_particles.chunk_by(|x, y| x.0 == y.0) {
            let j = group[0].0 as usize;
            for &(_, c, cc) in group {
                for &(_, d, cd) in group {
                    let normals = s.rows[c as usize].normal.dot(s.rows[d as usize].normal);
                    s.schur[c as usize * rows + d as usize] += cc * cd * w[j] * normals;
                }
            }
        }
        projected_gauss_seidel(
            &s.schur[..rows * rows],
            &s.offset[..rows],
            0.1 * contact_tolerance,
            &mut s.impulse[..rows],
            &mut s.contact_residual[..rows],
        );
        // λ = A⁻¹(−C) − Y μ.
        for k in 0..m {
            let row = &s.solved_columns[k * rows..(k + 1) * rows];
            s.rhs[k] -= dot(row, &s.impulse[..rows]);
        }
    }

    let direction: &[DVec2] = match direction_kind {
        ConstraintDirection::EndOfStep => &s.edge[..m],
        ConstraintDirection::StartOfStep => &s.start_direction[..m],
    };
    for (k, d) in direction.iter().enumerate() {
        let impulse = 2.0 * s.rhs[k] * *d;
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
    Ok(())
}

/// Assemble the tridiagonal (or cyclic) system of a chain and solve it for the
/// right-hand side in `s.rhs`, keeping the factor when contact columns will follow.
fn chain_solve(
    m: usize,
    closed: bool,
    direction_kind: ConstraintDirection,
    keep_factor: bool,
    s: &mut IslandScratch,
) -> Result<(), SingularPivot> {
    let particles = if closed { m } else { m + 1 };
    let next = |k: usize| if k + 1 == particles { 0 } else { k + 1 };
    let w = &s.inverse_mass;
    let direction: &[DVec2] = match direction_kind {
        ConstraintDirection::EndOfStep => &s.edge[..m],
        ConstraintDirection::StartOfStep => &s.start_direction[..m],
    };
    for k in 0..m {
        let prev_edge = if k == 0 { m - 1 } else { k - 1 };
        let next_edge = if k + 1 == m { 0 } else { k + 1 };
        let e = s.edge[k];
        s.diagonal[k] = 4.0 * (w[k] + w[next(k)]) * e.dot(direction[k]);
        s.lower[k] = -4.0 * w[k] * e.dot(direction[prev_edge]);
        s.upper[k] = -4.0 * w[next(k)] * e.dot(direction[next_edge]);
    }
    // A locked edge gets δ = 0: an identity row, and no coupling into its neighbours.
    for k in (0..m).filter(|&k| s.locked[k]) {
        s.diagonal[k] = 1.0;
        (s.lower[k], s.upper[k]) = (0.0, 0.0);
        if k + 1 < m || closed {
            s.lower[if k + 1 == m { 0 } else { k + 1 }] = 0.0;
        }
        if k > 0 || closed {
            s.upper[if k == 0 { m - 1 } else { k - 1 }] = 0.0;
        }
    }
    if !closed {
        // An open chain's first and last rows have no outer neighbours.
        s.lower[0] = 0.0;
        s.upper[m - 1] = 0.0;
    }
    if closed && m >= 3 {
        s.factors
            .cyclic
            .factor(&s.lower[..m], &s.diagonal[..m], &s.upper[..m])?;
        s.factors.cyclic.solve(&mut s.rhs[..m]);
    } else if keep_factor {
        s.factors
            .open
            .factor(&s.lower[..m], &s.diagonal[..m], &s.upper[..m])?;
        s.factors.open.solve(&mut s.rhs[..m]);
    } else {
        // One right-hand side: the fused single-pass Thomas solve is fastest.
        solve_tridiagonal(
            &s.lower[..m],
            &s.diagonal[..m],
            &s.upper[..m],
            &mut s.rhs[..m],
            &mut s.thomas[..m],
        )?;
    }
    Ok(())
}

/// Assemble `J W Jᵀ` of a tree or graph (end-of-step direction) into its sparse factor,
/// factor it and solve for the right-hand side in `s.rhs`.
fn graph_solve(m: usize, layout: &GraphLayout, s: &mut IslandScratch) -> Result<(), SingularPivot> {
    let w = &s.inverse_mass;
    let values = s.factors.sparse.values_mut(&layout.plan);
    let edges = layout.ends.iter().zip(&s.edge[..m]).zip(&s.locked[..m]);
    for (value, ((&(a, b), e), &locked)) in values.iter_mut().zip(edges) {
        *value = if locked {
            1.0
        } else {
            4.0 * (w[a as usize] + w[b as usize]) * e.length_squared()
        };
    }
    for c in &layout.couplings {
        let (k, l) = (c.k as usize, c.l as usize);
        if !s.locked[k] && !s.locked[l] {
            values[c.value as usize] +=
                4.0 * w[c.particle as usize] * c.sign * s.edge[k].dot(s.edge[l]);
        }
    }
    s.factors.sparse.factor(&layout.plan)?;
    s.factors.sparse.solve(&layout.plan, &mut s.rhs[..m]);
    Ok(())
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solve the complementarity problem `S μ + q ≥ 0, μ ≥ 0, μ·(S μ + q) = 0` for a small
/// symmetric positive semidefinite `S` (row-major) by projected Gauss–Seidel, until no
/// sweep moves any row's residual by more than `tolerance`. The residual `S μ + q` is
/// kept up to date as μ changes, so rows that stay inactive cost nothing.
fn projected_gauss_seidel(
    schur: &[f64],
    offset: &[f64],
    tolerance: f64,
    mu: &mut [f64],
    residual: &mut [f64],
) {
    let n = offset.len();
    mu.fill(0.0);
    residual.copy_from_slice(offset);
    for _sweep in 0..200 {
        let mut change = 0.0f64;
        for c in 0..n {
            let diagonal = schur[c * n + c];
            if diagonal <= 0.0 {
                continue;
            }
            let updated = (mu[c] - residual[c] / diagonal).max(0.0);
            let delta = updated - mu[c];
            if delta == 0.0 {
                continue;
            }
            mu[c] = updated;
            // S is symmetric: column c is row c.
            for (r, s) in residual.iter_mut().zip(&schur[c * n..(c + 1) * n]) {
                *r += s * delta;
            }
            change = change.max(delta.abs() * diagonal);
        }
        if change <= tolerance {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    fn chain_edges(points: &[DVec2], closed: bool) -> Vec<IslandEdge> {
        let n = points.len() as u32;
        let m = if closed { n } else { n - 1 };
        let pairs: Vec<(u32, u32)> = (0..m).map(|k| (k, (k + 1) % n)).collect();
        IslandEdge::between(points, &pairs)
    }

    fn settings(direction: ConstraintDirection) -> ProjectionSettings {
        ProjectionSettings {
            tolerance: 1e-13,
            max_iterations: 50,
            direction,
            contact_tolerance: 1e-12,
            max_correction: f64::INFINITY,
        }
    }

    struct Case<'a> {
        edges: &'a [IslandEdge],
        closed: bool,
        position: &'a [DVec2],
        inverse_mass: &'a [f64],
        contacts: &'a [ContactRow],
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
                Bodies {
                    position: self.position,
                    velocity,
                    inverse_mass: self.inverse_mass,
                },
                self.contacts,
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
                contacts: &[],
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
            Bodies {
                position,
                velocity,
                inverse_mass,
            },
            &[],
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
                contacts: &[],
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
            contacts: &[],
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
            contacts: &[],
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
            contacts: &[],
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

    #[test]
    fn contacts_hold_while_edges_stay_exact() {
        // A strand lying on a floor, its first particle in contact (normal +y); the
        // middle particle is kicked down or up, pulling the others along.
        let n = 6;
        let points: Vec<DVec2> = (0..n).map(|i| DVec2::new(0.1 * i as f64, 0.0)).collect();
        let edges = chain_edges(&points, false);
        let floor = n as u32; // a pinned particle standing for the floor
        let inverse_mass = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0];
        for kick in [-2.0, 2.0] {
            let mut velocity = vec![DVec2::ZERO; n + 1];
            velocity[2] = DVec2::new(0.0, kick);
            let contact = ContactRow::point_edge(0, floor, floor, 0.0, DVec2::Y, &velocity);
            let contacts = [contact];
            let case = Case {
                edges: &edges,
                closed: false,
                position: &points,
                inverse_mass: &inverse_mass,
                contacts: &contacts,
                dt: 0.01,
            };
            let mut v = velocity.clone();
            let outcome = case.project(&mut v, ConstraintDirection::EndOfStep);
            assert!(outcome.converged, "{outcome:?}");
            assert!(case.max_relative_error(&v) < 1e-12);
            // Met up to the final edge polish: a millionth of an edge per step.
            let polish = POLISH_RESIDUAL * 0.1 / case.dt;
            assert!(contact.normal_velocity(&v) >= contact.target - polish);
            if kick < 0.0 {
                // Pulled down into the floor: the contact holds it.
                assert!(v[0].y.abs() <= polish, "{}", v[0].y);
            } else {
                // Pulled up, away from the floor: the contact lets go.
                assert!(v[0].y > 1e-6, "{}", v[0].y);
            }
        }
    }

    #[test]
    fn a_strand_lying_on_another_is_held_by_a_relative_contact() {
        // Strand A (particles 0..4, vertical) comes down onto strand B (5..9, flat):
        // A's lowest particle touches B's edge (6, 7) halfway. Both are free, so the
        // contact limits their relative motion, not either one's own.
        let mut points: Vec<DVec2> = (0..5)
            .map(|i| DVec2::new(0.43, 0.004 + 0.02 * i as f64))
            .collect();
        points.extend((0..5).map(|i| DVec2::new(0.40 + 0.02 * i as f64, 0.0)));
        let upper = chain_edges(&points[..5], false);
        let lower: Vec<IslandEdge> = chain_edges(&points[5..], false)
            .into_iter()
            .map(|e| IslandEdge {
                a: e.a + 5,
                b: e.b + 5,
                ..e
            })
            .collect();
        let mut velocity = vec![DVec2::ZERO; 10];
        velocity[..5].fill(DVec2::new(0.3, -1.0));
        velocity[1] = DVec2::new(0.3, -2.0); // compresses A's first edge: pushes 0 down
        let contact = ContactRow::point_edge(0, 6, 7, 0.5, DVec2::Y, &velocity);
        // Without the contact, A's projection would drive particle 0 into B.
        let mut free = velocity.clone();
        let case = Case {
            edges: &upper,
            closed: false,
            position: &points,
            inverse_mass: &[1.0; 10],
            contacts: &[],
            dt: 0.01,
        };
        case.project(&mut free, ConstraintDirection::EndOfStep);
        assert!(contact.normal_velocity(&free) < contact.target - 0.1);
        // Each strand projected with the other frozen, as the island sweep does.
        for chain in [&upper, &lower] {
            let case = Case {
                edges: chain,
                closed: false,
                position: &points,
                inverse_mass: &[1.0; 10],
                contacts: &[contact],
                dt: 0.01,
            };
            let mut v = velocity.clone();
            let outcome = case.project(&mut v, ConstraintDirection::EndOfStep);
            assert!(outcome.converged, "{outcome:?}");
            assert!(case.max_relative_error(&v) < 1e-12);
            let polish = POLISH_RESIDUAL * 0.02 / case.dt;
            assert!(contact.normal_velocity(&v) >= contact.target - polish);
        }
    }
}
