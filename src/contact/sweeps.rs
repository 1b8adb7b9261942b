//! The contact rows of a contact projection: their local form, the parts' responses to
//! them, and the projected Gauss–Seidel sweeps that find their impulses.
//!
//! A row's response on a part is kept twice: per particle (`r = W f − W Jᵀ y`, what
//! the sweeps add to the corrections when the row's impulse changes) and per edge
//! (`y = A⁻¹ J W f`, the multipliers it asks of the part's edges, summed once per
//! Newton step for the edges' tensions).
//!
//! The rows come in three groups (`split`): side 0's, side 1's, and those
//! between. Each sweep visits them in that order; the two sides' rows move disjoint
//! particles, so on two threads they are swept at once, and the result is the same.

use bevy::math::DVec2;

use super::local_row::LocalRow;
use super::rows::{ContactRow, RowImpulse};
use super::scratch::{Bank, ContactScratch, LOOSE, NOT_LOCAL, Part};
use crate::constraints::islands::IslandSet;
use crate::constraints::projection::scratch::Factors;
use crate::constraints::projection::view::IslandView;
use crate::constraints::projection::walk::{ChainWalk, Walk, with_walk};
use crate::parallel::{Partner, with_partner};

/// Translate `rows` into local rows in the cut's sweep order (a row with no free
/// particle among the parts stays inert), warm-started from `impulses`.
pub(super) fn localize_rows(
    rows: &[ContactRow],
    impulses: &[RowImpulse],
    velocity: &[DVec2],
    dt: f64,
    s: &mut ContactScratch,
) {
    s.rows.clear();
    for bank in &mut s.banks {
        bank.placed = (0, 0);
    }
    for i in 0..s.cut.rows.len() {
        let c = s.cut.rows[i] as usize;
        let row = &rows[c];
        let tangent = row.normal.perp();
        let along = |direction: DVec2| -> f64 {
            (row.particles.iter().zip(row.coefficients))
                .map(|(&p, k)| k * direction.dot(velocity[p as usize]))
                .sum()
        };
        let warm = impulses.get(c).copied().unwrap_or_default();
        let mu_n = (warm.normal * dt).max(0.0);
        let cone = row.friction * mu_n;
        let mut local = LocalRow {
            normal: row.normal,
            slack_n: (along(row.normal) - row.target) * dt,
            slack_t: along(tangent) * dt,
            friction: row.friction,
            mu_n,
            mu_t: (warm.tangent * dt).clamp(-cone, cone),
            ..Default::default()
        };
        for (&p, &coefficient) in row.particles.iter().zip(&row.coefficients) {
            let j = s.local_of.get(p as usize).copied().unwrap_or(NOT_LOCAL);
            if j == NOT_LOCAL || coefficient == 0.0 {
                continue;
            }
            local.entries[local.count as usize] = (j, coefficient);
            local.count += 1;
            let part = part_of(&s.parts, j) as u32;
            if !local.links[..local.link_count as usize]
                .iter()
                .any(|&(q, ..)| q == part)
            {
                local.links[local.link_count as usize] = (part, UNPLACED, UNPLACED);
                local.link_count += 1;
            }
        }
        if local.count == 0 {
            local.mu_n = 0.0;
            local.mu_t = 0.0;
        }
        s.rows.push(local);
    }
    for &p in &s.packed {
        s.local_of[p as usize] = NOT_LOCAL;
    }
}

/// A link's response offsets before its row first takes an impulse.
const UNPLACED: u32 = u32::MAX;

/// Give link `link` of `row` room for its responses in its group's bank, after those
/// placed so far in this projection. Only rows that take an impulse are placed: in the
/// fur three rows in four never do, and room for every row was most of the
/// projection's memory (and, on a first step, its page faults). Each response is
/// written in full before it is read.
fn place(bank: &mut Bank, parts: &[Part], row: &mut LocalRow, link: usize) {
    let (part, particle_offset, _) = row.links[link];
    if particle_offset != UNPLACED {
        return;
    }
    let (_, particles) = parts[part as usize].particles;
    let (_, edges) = parts[part as usize].edges;
    let (particle_offset, edge_offset) = bank.placed;
    row.links[link] = (part, particle_offset, edge_offset);
    bank.placed = (particle_offset + 2 * particles, edge_offset + 2 * edges);
    let (particle_end, edge_end) = (bank.placed.0 as usize, bank.placed.1 as usize);
    if bank.particle_responses.len() < particle_end {
        bank.particle_responses.resize(particle_end, DVec2::ZERO);
    }
    if bank.responses.len() < edge_end {
        bank.responses.resize(edge_end, 0.0);
    }
}

/// The part holding local particle `j` (parts are laid out in particle order).
fn part_of(parts: &[Part], j: u32) -> usize {
    parts.partition_point(|p| p.particles.0 + p.particles.1 <= j)
}

/// What the sweeps of one Newton step read and never write: the parts, their edges
/// and their factors.
#[derive(Clone, Copy)]
struct Frame<'a> {
    set: &'a IslandSet,
    islands: &'a [u32],
    parts: &'a [Part],
    inverse_mass: &'a [f64],
    incident: &'a [(u32, f64)],
    incident_start: &'a [u32],
    ends: &'a [(u32, u32)],
    edge: &'a [DVec2],
    locked: &'a [bool],
    part_factors: &'a [Factors],
}

/// Row `row`'s responses on each part it touches, normal and tangent: `y = A⁻¹ J W f`
/// with the part's latest factor (a part without one — a loose particle, a singular
/// system — moves by the direct impulse alone), each particle's `r = W (f − Jᵀ y)`,
/// and the row's stiffness along both. Computed once per projection, when the row
/// first takes an impulse: later Newton steps keep it (a response one linearization
/// old is still a fine direction for the sweeps; the edges' own Newton steps keep
/// them exact).
fn row_responses(f: &Frame, bank: &mut Bank, row: &mut LocalRow) {
    for link in 0..row.link_count as usize {
        place(bank, f.parts, row, link);
        let part = f.parts[row.links[link].0 as usize];
        let factored = part.island != LOOSE && part.edges.1 > 0 && part.factored;
        if !factored {
            link_responses(f, bank, row, link, None::<ChainWalk>);
            continue;
        }
        with_walk!(
            IslandView::of(f.set, f.islands[part.island as usize] as usize),
            |_, walk| link_responses(f, bank, row, link, Some(walk))
        );
    }
    let tangent = row.normal.perp();
    row.diag_n = stiffness(f, bank, row, Along::Normal, row.normal);
    row.diag_t = stiffness(f, bank, row, Along::Tangent, tangent);
    row.cross = stiffness(f, bank, row, Along::Normal, tangent);
    row.ready = true;
}

/// Link `link` of `row`: its part's responses, solved by `walk` with the part's
/// factor, or the direct impulse alone without one.
fn link_responses<W: Walk>(
    f: &Frame,
    bank: &mut Bank,
    row: &LocalRow,
    link: usize,
    walk: Option<W>,
) {
    let (p, particle_offset, edge_offset) = row.links[link];
    let part = f.parts[p as usize];
    let (first, particles) = (part.particles.0 as usize, part.particles.1 as usize);
    let (first_edge, m) = (part.edges.0 as usize, part.edges.1 as usize);
    let (particle_offset, edge_offset) = (particle_offset as usize, edge_offset as usize);
    let in_part = |j: u32| (first..first + particles).contains(&(j as usize));
    // Two right-hand sides row by row: column 0 the normal, column 1 the tangent.
    let columns = &mut bank.responses[edge_offset..edge_offset + 2 * m];
    columns.fill(0.0);
    if let Some(walk) = walk {
        let tangent = row.normal.perp();
        for &(j, coefficient) in &row.entries[..row.count as usize] {
            if !in_part(j) {
                continue;
            }
            let w = f.inverse_mass[j as usize] * coefficient;
            let range =
                f.incident_start[j as usize] as usize..f.incident_start[j as usize + 1] as usize;
            for &(edge, sign) in &f.incident[range] {
                let edge = edge as usize;
                if f.locked[edge] {
                    continue;
                }
                let d = 2.0 * sign * w * f.edge[edge];
                let i = 2 * (edge - first_edge);
                columns[i] += d.dot(row.normal);
                columns[i + 1] += d.dot(tangent);
            }
        }
        walk.solve_many(m, &f.part_factors[p as usize], columns, 2);
    }
    // r = W (f − Jᵀ y) over the part's particles, edge by edge: an edge's multiplier
    // pulls its start along it and its end back (a locked edge's is zero).
    let (normal, tangent) = (row.normal, row.normal.perp());
    let y = &bank.responses[edge_offset..edge_offset + 2 * m];
    let r = &mut bank.particle_responses[particle_offset..particle_offset + 2 * particles];
    r.fill(DVec2::ZERO);
    let (r_n, r_t) = r.split_at_mut(particles);
    // Starts first, then ends: along a chain an edge's end is the next one's start,
    // and in one loop each update would wait on the last one's store.
    for k in 0..m {
        let a = f.ends[first_edge + k].0 as usize;
        let d = 2.0 * f.inverse_mass[a] * f.edge[first_edge + k];
        r_n[a - first] += y[2 * k] * d;
        r_t[a - first] += y[2 * k + 1] * d;
    }
    for k in 0..m {
        let b = f.ends[first_edge + k].1 as usize;
        let d = 2.0 * f.inverse_mass[b] * f.edge[first_edge + k];
        r_n[b - first] -= y[2 * k] * d;
        r_t[b - first] -= y[2 * k + 1] * d;
    }
    for &(j, coefficient) in &row.entries[..row.count as usize] {
        if in_part(j) {
            let (local, w) = (j as usize - first, f.inverse_mass[j as usize] * coefficient);
            r_n[local] += w * normal;
            r_t[local] += w * tangent;
        }
    }
}

/// The corrections a group of rows reads.
trait Corrections {
    /// Local particle `j`'s correction.
    fn at(&self, j: usize) -> DVec2;
}

/// Every local particle's corrections.
impl Corrections for [DVec2] {
    #[inline]
    fn at(&self, j: usize) -> DVec2 {
        self[j]
    }
}

/// The corrections a group of rows reads and writes.
trait CorrectionsMut: Corrections {
    /// The corrections of the `count` local particles from `first` (one part's).
    fn run_mut(&mut self, first: usize, count: usize) -> &mut [DVec2];
}

/// The corrections of the local particles from `first` on.
struct Run<'a> {
    first: usize,
    values: &'a mut [DVec2],
}

impl Corrections for Run<'_> {
    #[inline]
    fn at(&self, j: usize) -> DVec2 {
        self.values[j - self.first]
    }
}

impl CorrectionsMut for Run<'_> {
    #[inline]
    fn run_mut(&mut self, first: usize, count: usize) -> &mut [DVec2] {
        &mut self.values[first - self.first..][..count]
    }
}

/// Side 0's corrections and side 1's, which start at local particle `split`: what the
/// rows between the sides see.
struct Sides<'a> {
    low: &'a mut [DVec2],
    high: &'a mut [DVec2],
    split: usize,
}

impl Corrections for Sides<'_> {
    #[inline]
    fn at(&self, j: usize) -> DVec2 {
        match j.checked_sub(self.split) {
            Some(k) => self.high[k],
            None => self.low[j],
        }
    }
}

impl CorrectionsMut for Sides<'_> {
    #[inline]
    fn run_mut(&mut self, first: usize, count: usize) -> &mut [DVec2] {
        // A part lies on one side.
        match first.checked_sub(self.split) {
            Some(k) => &mut self.high[k..k + count],
            None => &mut self.low[first..first + count],
        }
    }
}

/// The sweeps over the rows.
pub(super) struct Sweeps;

/// Along the normal or the tangent.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Along {
    Normal,
    Tangent,
}

/// What the partner thread is asked to do with side 1's rows.
enum Job<'a> {
    /// Apply the warm start (`true` on a Newton step's first projection call).
    Warm(&'a mut [DVec2], bool),
    /// One sweep.
    Sweep(&'a mut [DVec2]),
}

/// Where side 1's jobs run: handed over now, their results taken later.
trait SideOne<'a> {
    fn send(&mut self, job: Job<'a>);
    fn wait(&mut self) -> (&'a mut [DVec2], f64);
}

/// Side 1's jobs on the partner thread.
impl<'a> SideOne<'a> for &Partner<Job<'a>, (&'a mut [DVec2], f64)> {
    fn send(&mut self, job: Job<'a>) {
        Partner::send(self, job);
    }

    fn wait(&mut self) -> (&'a mut [DVec2], f64) {
        Partner::wait(self)
    }
}

/// Side 1's jobs on this thread, each run as it is handed over.
struct Inline<'a, F> {
    work: F,
    result: Option<(&'a mut [DVec2], f64)>,
}

impl<'a, F: FnMut(Job<'a>) -> (&'a mut [DVec2], f64)> SideOne<'a> for Inline<'a, F> {
    fn send(&mut self, job: Job<'a>) {
        self.result = Some((self.work)(job));
    }

    fn wait(&mut self) -> (&'a mut [DVec2], f64) {
        self.result.take().expect("a job was handed over")
    }
}

/// A contact projection's contact solve: side 0's rows here, side 1's wherever `SideOne`
/// runs them, at the same time, then the rows between; the same order on either (a
/// problem that is not cut has only rows between).
struct CutSweeps<'f, 'a> {
    frame: &'f Frame<'f>,
    rows_0: &'a mut [LocalRow],
    bank_0: &'a mut Bank,
    between: &'a mut [LocalRow],
    bank_between: &'a mut Bank,
    split: usize,
    first: bool,
    cap: u32,
    tolerance: f64,
}

impl<'a> CutSweeps<'_, 'a> {
    /// The warm start and the sweeps over side 0's corrections `low` and side 1's
    /// `high`; returns the sweeps done.
    fn run(
        self,
        low: &'a mut [DVec2],
        high: &'a mut [DVec2],
        side_1: &mut impl SideOne<'a>,
    ) -> u32 {
        let f = self.frame;
        side_1.send(Job::Warm(high, self.first));
        let mut side_0 = Run {
            first: 0,
            values: low,
        };
        warm(f, self.bank_0, self.rows_0, &mut side_0, self.first);
        let (high, _) = side_1.wait();
        let mut sides = Sides {
            low: side_0.values,
            high,
            split: self.split,
        };
        warm(f, self.bank_between, self.between, &mut sides, self.first);
        let mut sweeps = 0;
        while sweeps < self.cap {
            sweeps += 1;
            let Sides { low, high, .. } = sides;
            side_1.send(Job::Sweep(high));
            let mut side_0 = Run {
                first: 0,
                values: low,
            };
            let worst_0 = sweep(f, self.bank_0, self.rows_0, &mut side_0);
            let (high, worst_1) = side_1.wait();
            sides = Sides {
                low: side_0.values,
                high,
                split: self.split,
            };
            let worst = sweep(f, self.bank_between, self.between, &mut sides);
            if worst.max(worst_0).max(worst_1) <= self.tolerance {
                break;
            }
        }
        sweeps
    }
}

impl Sweeps {
    /// How far (a distance per step) the most violated normal row falls short at the
    /// current corrections.
    /// How far (a distance per step) `row`'s normal part falls short at the current
    /// corrections (negative: met with room to spare).
    pub(super) fn row_shortfall(s: &ContactScratch, row: &LocalRow) -> f64 {
        if row.count == 0 {
            return 0.0;
        }
        -(row.slack_n + moved(s.correction.as_slice(), row, row.normal))
    }

    pub(super) fn shortfall(s: &ContactScratch) -> f64 {
        let correction = s.correction.as_slice();
        s.rows
            .iter()
            .filter(|row| row.count > 0)
            .map(|row| -(row.slack_n + moved(correction, row, row.normal)))
            .fold(0.0, f64::max)
    }

    /// One Newton step's contact solve from `s.base` (the edge correction), with the
    /// responses computed: projected Gauss–Seidel until no normal row falls short by
    /// more than `tolerance` or `cap` sweeps are done; the new corrections into
    /// `s.correction`, the rows' edge multipliers into `s.contact_multiplier`. On the
    /// first Newton step the warm start is applied first. Returns the sweeps done.
    pub(super) fn run(
        set: &IslandSet,
        islands: &[u32],
        s: &mut ContactScratch,
        first: bool,
        cap: u32,
        tolerance: f64,
    ) -> u32 {
        s.correction.copy_from_slice(&s.base);
        let frame = Frame {
            set,
            islands,
            parts: &s.parts,
            inverse_mass: &s.inverse_mass,
            incident: &s.incident,
            incident_start: &s.incident_start,
            ends: &s.ends,
            edge: &s.edge,
            locked: &s.locked,
            part_factors: &s.part_factors,
        };
        let (end_0, end_1) = s.cut.row_ends;
        let (rows_0, rest) = s.rows.split_at_mut(end_0);
        let (rows_1, between) = rest.split_at_mut(end_1 - end_0);
        let [bank_0, bank_1, bank_between] = &mut s.banks;
        let split = s.side_1;
        let (low, high) = s.correction.split_at_mut(split);
        let f = &frame;
        // Side 1's rows: on a partner thread with two threads, here otherwise. A problem
        // that is not cut has every particle on side 0 and every row between.
        let cut = !rows_0.is_empty() || !rows_1.is_empty();
        let side_1 = |job| match job {
            Job::Warm(values, first) => {
                let mut run = Run {
                    first: split,
                    values,
                };
                warm(f, bank_1, rows_1, &mut run, first);
                (run.values, 0.0)
            }
            Job::Sweep(values) => {
                let mut run = Run {
                    first: split,
                    values,
                };
                let worst = sweep(f, bank_1, rows_1, &mut run);
                (run.values, worst)
            }
        };
        let sides = CutSweeps {
            frame: f,
            rows_0,
            bank_0,
            between,
            bank_between,
            split,
            first,
            cap,
            tolerance,
        };
        let sweeps = if s.threads <= 1 || !cut {
            sides.run(
                low,
                high,
                &mut Inline {
                    work: side_1,
                    result: None,
                },
            )
        } else {
            with_partner(side_1, |partner| sides.run(low, high, &mut &*partner))
        };
        multipliers(s);
        sweeps
    }
}

/// Start a Newton step's contact solve for `rows`: note the impulses it starts from
/// (none on the first, whose warm start is then applied as a change).
fn warm(
    f: &Frame,
    bank: &mut Bank,
    rows: &mut [LocalRow],
    c: &mut impl CorrectionsMut,
    first: bool,
) {
    for row in rows {
        if first {
            (row.start_n, row.start_t) = (0.0, 0.0);
        } else {
            (row.start_n, row.start_t) = (row.mu_n, row.mu_t);
        }
        let (warm_n, warm_t) = (row.mu_n - row.start_n, row.mu_t - row.start_t);
        if warm_n != 0.0 || warm_t != 0.0 {
            if !row.ready {
                row_responses(f, bank, row);
            }
            apply(f, bank, row, c, warm_n, warm_t);
        }
    }
}

/// One projected Gauss–Seidel sweep over `rows`; returns how far the most violated
/// normal row fell short before its update.
fn sweep(f: &Frame, bank: &mut Bank, rows: &mut [LocalRow], c: &mut impl CorrectionsMut) -> f64 {
    let mut worst = 0.0f64;
    for row in rows {
        if row.count == 0 {
            continue;
        }
        let value = row.slack_n + moved(c, row, row.normal);
        if value >= 0.0 && row.mu_n == 0.0 && row.mu_t == 0.0 {
            continue; // met with no impulse: nothing to do
        }
        worst = worst.max(-value);
        if !row.ready {
            row_responses(f, bank, row);
        }
        if row.diag_n <= 0.0 {
            continue;
        }
        // Normal first, then the tangent as the normal change leaves it (the two
        // share one pass over the corrections).
        let mu_n = (row.mu_n - value / row.diag_n).max(0.0);
        let change_n = mu_n - row.mu_n;
        let mut change_t = 0.0;
        if row.friction > 0.0 && row.diag_t > 0.0 && (mu_n > 0.0 || row.mu_t != 0.0) {
            let value = row.slack_t + moved(c, row, row.normal.perp()) + change_n * row.cross;
            let cone = row.friction * mu_n;
            change_t = (row.mu_t - value / row.diag_t).clamp(-cone, cone) - row.mu_t;
        }
        row.mu_n = mu_n;
        row.mu_t += change_t;
        apply(f, bank, row, c, change_n, change_t);
    }
    worst
}

/// `Σ cᵢ d·Δᵢ` of `row` along `d` for the corrections `c`.
#[inline]
fn moved<C: Corrections + ?Sized>(c: &C, row: &LocalRow, d: DVec2) -> f64 {
    row.entries[..row.count as usize]
        .iter()
        .map(|&(j, coefficient)| coefficient * d.dot(c.at(j as usize)))
        .sum()
}

/// The particle responses of link `link` of `row` along `along`: the part's first
/// local particle and the responses.
fn particle_response<'b>(
    f: &Frame,
    bank: &'b Bank,
    row: &LocalRow,
    link: usize,
    along: Along,
) -> (usize, &'b [DVec2]) {
    let (part, offset, _) = row.links[link];
    let (first, particles) = f.parts[part as usize].particles;
    let (first, particles) = (first as usize, particles as usize);
    let start = offset as usize
        + if along == Along::Tangent {
            particles
        } else {
            0
        };
    (first, &bank.particle_responses[start..start + particles])
}

/// `Σ cᵢ d·rᵢ` over `row`'s particles for its responses `r` along `along`: its own
/// stiffness with `d` the same direction, the cross term with the other.
fn stiffness(f: &Frame, bank: &Bank, row: &LocalRow, along: Along, d: DVec2) -> f64 {
    let mut value = 0.0;
    for link in 0..row.link_count as usize {
        let (first, r) = particle_response(f, bank, row, link, along);
        for &(j, coefficient) in &row.entries[..row.count as usize] {
            if let Some(r) = r.get((j as usize).wrapping_sub(first)) {
                value += coefficient * d.dot(*r);
            }
        }
    }
    value
}

/// Add `normal` and `tangent` of `row`'s impulses to the corrections.
fn apply(
    f: &Frame,
    bank: &Bank,
    row: &LocalRow,
    c: &mut impl CorrectionsMut,
    normal: f64,
    tangent: f64,
) {
    if normal == 0.0 && tangent == 0.0 {
        return;
    }
    for &(part, offset, _) in &row.links[..row.link_count as usize] {
        let (first, particles) = f.parts[part as usize].particles;
        let (first, particles) = (first as usize, particles as usize);
        let offset = offset as usize;
        let correction = c.run_mut(first, particles);
        let r = &bank.particle_responses[offset..offset + 2 * particles];
        let (r_n, r_t) = r.split_at(particles);
        // As flat coordinates: the same sums, but the loop vectorizes over them without
        // the shuffles a loop over pairs gets.
        let correction: &mut [f64] = bytemuck::cast_slice_mut(correction);
        let (r_n, r_t): (&[f64], &[f64]) = (bytemuck::cast_slice(r_n), bytemuck::cast_slice(r_t));
        for ((x, n), t) in correction.iter_mut().zip(r_n).zip(r_t) {
            *x += normal * *n + tangent * *t;
        }
    }
}

/// The edge multipliers of this Newton step's contact impulses, `Σ dμ y`, per local
/// edge (for the edges' tensions), the rows in sweep order.
fn multipliers(s: &mut ContactScratch) {
    s.contact_multiplier.fill(0.0);
    let (end_0, end_1) = s.cut.row_ends;
    for (c, row) in s.rows.iter().enumerate() {
        let bank = &s.banks[if c < end_0 {
            0
        } else if c < end_1 {
            1
        } else {
            2
        }];
        for (along, amount) in [row.mu_n - row.start_n, row.mu_t - row.start_t]
            .into_iter()
            .enumerate()
        {
            if amount == 0.0 {
                continue;
            }
            for &(part, _, offset) in &row.links[..row.link_count as usize] {
                let (first_edge, m) = s.parts[part as usize].edges;
                let (first_edge, m) = (first_edge as usize, m as usize);
                let y = &bank.responses[offset as usize..offset as usize + 2 * m];
                let x = &mut s.contact_multiplier[first_edge..first_edge + m];
                for (x, y) in x.iter_mut().zip(y.chunks_exact(2)) {
                    *x += amount * y[along];
                }
            }
        }
    }
}
