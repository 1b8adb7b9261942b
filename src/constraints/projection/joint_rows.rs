//! The contact rows of a joint projection: their joint form, the parts' responses to
//! them, and the projected Gauss–Seidel sweeps that find their impulses.
//!
//! A row's response on a part is kept twice: per particle (`r = W f − W Jᵀ y`, what
//! the sweeps add to the corrections when the row's impulse changes) and per edge
//! (`y = A⁻¹ J W f`, the multipliers it asks of the part's edges, summed once per
//! Newton step for the edges' tensions).

use bevy::math::DVec2;

use super::contact_rows::ContactRow;
use super::joint_state::{JointRow, JointScratch, LOOSE, NOT_JOINT, RowImpulse};
use super::view::IslandView;
use super::walk::{ChainWalk, GraphWalk, Walk};
use crate::constraints::islands::IslandSet;

/// Translate `rows` into joint rows (one each, in order; a row with no free particle
/// among the parts stays inert), warm-started from `impulses`.
pub(super) fn localize_rows(
    rows: &[ContactRow],
    impulses: &[RowImpulse],
    velocity: &[DVec2],
    dt: f64,
    s: &mut JointScratch,
) {
    s.rows.clear();
    s.placed = (0, 0);
    for (c, row) in rows.iter().enumerate() {
        let tangent = row.normal.perp();
        let along = |direction: DVec2| -> f64 {
            (row.particles.iter().zip(row.coefficients))
                .map(|(&p, k)| k * direction.dot(velocity[p as usize]))
                .sum()
        };
        let warm = impulses.get(c).copied().unwrap_or_default();
        let mu_n = (warm.normal * dt).max(0.0);
        let cone = row.friction * mu_n;
        let mut joint = JointRow {
            normal: row.normal,
            slack_n: (along(row.normal) - row.target) * dt,
            slack_t: along(tangent) * dt,
            friction: row.friction,
            mu_n,
            mu_t: (warm.tangent * dt).clamp(-cone, cone),
            ..Default::default()
        };
        for (&p, &coefficient) in row.particles.iter().zip(&row.coefficients) {
            let j = s.joint_of.get(p as usize).copied().unwrap_or(NOT_JOINT);
            if j == NOT_JOINT || coefficient == 0.0 {
                continue;
            }
            joint.entries[joint.count as usize] = (j, coefficient);
            joint.count += 1;
            let part = part_of(s, j) as u32;
            if !joint.links[..joint.link_count as usize]
                .iter()
                .any(|&(q, ..)| q == part)
            {
                joint.links[joint.link_count as usize] = (part, UNPLACED, UNPLACED);
                joint.link_count += 1;
            }
        }
        if joint.count == 0 {
            joint.mu_n = 0.0;
            joint.mu_t = 0.0;
        }
        s.rows.push(joint);
    }
    for &p in &s.packed {
        s.joint_of[p as usize] = NOT_JOINT;
    }
}

/// A link's response offsets before its row first takes an impulse.
const UNPLACED: u32 = u32::MAX;

/// Give link `link` of row `c` room for its responses, after those placed so far in
/// this projection. Only rows that take an impulse are placed: in the fur three rows
/// in four never do, and room for every row was most of the projection's memory (and,
/// on a first step, its page faults). Each response is written in full before it is
/// read.
fn place(s: &mut JointScratch, c: usize, link: usize) {
    let (part, particle_offset, _) = s.rows[c].links[link];
    if particle_offset != UNPLACED {
        return;
    }
    let (_, particles) = s.parts[part as usize].particles;
    let (_, edges) = s.parts[part as usize].edges;
    let (particle_offset, edge_offset) = s.placed;
    s.rows[c].links[link] = (part, particle_offset, edge_offset);
    s.placed = (particle_offset + 2 * particles, edge_offset + 2 * edges);
    let (particle_end, edge_end) = (s.placed.0 as usize, s.placed.1 as usize);
    if s.particle_responses.len() < particle_end {
        s.particle_responses.resize(particle_end, DVec2::ZERO);
    }
    if s.responses.len() < edge_end {
        s.responses.resize(edge_end, 0.0);
    }
}

/// The part holding joint particle `j` (parts are laid out in particle order).
fn part_of(s: &JointScratch, j: u32) -> usize {
    s.parts
        .partition_point(|p| p.particles.0 + p.particles.1 <= j)
}

/// Row `c`'s responses on each part it touches, normal and tangent: `y = A⁻¹ J W f`
/// with the part's latest factor (a part without one — a loose particle, a singular
/// system — moves by the direct impulse alone), each particle's `r = W (f − Jᵀ y)`,
/// and the row's stiffness along both. Computed once per projection, when the row
/// first takes an impulse: later Newton steps keep it (a response one linearization
/// old is still a fine direction for the sweeps; the edges' own Newton steps keep
/// them exact).
fn row_responses(set: &IslandSet, islands: &[u32], s: &mut JointScratch, c: usize) {
    for link in 0..s.rows[c].link_count as usize {
        place(s, c, link);
        let part = s.parts[s.rows[c].links[link].0 as usize];
        let factored = part.island != LOOSE && part.edges.1 > 0 && part.factored;
        if !factored {
            link_responses(c, link, None::<ChainWalk>, s);
            continue;
        }
        match IslandView::of(set, islands[part.island as usize] as usize) {
            IslandView::Chain(chain) => link_responses(
                c,
                link,
                Some(ChainWalk {
                    closed: chain.closed,
                }),
                s,
            ),
            IslandView::Graph(graph) => link_responses(
                c,
                link,
                Some(GraphWalk {
                    layout: graph.layout,
                }),
                s,
            ),
        }
    }
    let tangent = s.rows[c].normal.perp();
    let diag_n = stiffness(s, c, Along::Normal, s.rows[c].normal);
    let diag_t = stiffness(s, c, Along::Tangent, tangent);
    let cross = stiffness(s, c, Along::Normal, tangent);
    let row = &mut s.rows[c];
    (row.diag_n, row.diag_t, row.cross, row.ready) = (diag_n, diag_t, cross, true);
}

/// Link `link` of row `c`: its part's responses, solved by `walk` with the part's
/// factor, or the direct impulse alone without one.
fn link_responses<W: Walk>(c: usize, link: usize, walk: Option<W>, s: &mut JointScratch) {
    let row = s.rows[c];
    let (p, particle_offset, edge_offset) = row.links[link];
    let part = s.parts[p as usize];
    let (first, particles) = (part.particles.0 as usize, part.particles.1 as usize);
    let (first_edge, m) = (part.edges.0 as usize, part.edges.1 as usize);
    let (particle_offset, edge_offset) = (particle_offset as usize, edge_offset as usize);
    let in_part = |j: u32| (first..first + particles).contains(&(j as usize));
    // Two right-hand sides row by row: column 0 the normal, column 1 the tangent.
    let columns = &mut s.responses[edge_offset..edge_offset + 2 * m];
    columns.fill(0.0);
    if let Some(walk) = walk {
        let tangent = row.normal.perp();
        for &(j, coefficient) in &row.entries[..row.count as usize] {
            if !in_part(j) {
                continue;
            }
            let w = s.inverse_mass[j as usize] * coefficient;
            let range =
                s.incident_start[j as usize] as usize..s.incident_start[j as usize + 1] as usize;
            for &(edge, sign) in &s.incident[range] {
                let edge = edge as usize;
                if s.locked[edge] {
                    continue;
                }
                let d = 2.0 * sign * w * s.edge[edge];
                let i = 2 * (edge - first_edge);
                columns[i] += d.dot(row.normal);
                columns[i + 1] += d.dot(tangent);
            }
        }
        walk.solve_many(m, &s.part_factors[p as usize], columns, 2);
    }
    // r = W (f − Jᵀ y) over the part's particles, edge by edge: an edge's multiplier
    // pulls its start along it and its end back (a locked edge's is zero).
    let (normal, tangent) = (row.normal, row.normal.perp());
    let y = &s.responses[edge_offset..edge_offset + 2 * m];
    let r = &mut s.particle_responses[particle_offset..particle_offset + 2 * particles];
    r.fill(DVec2::ZERO);
    let (r_n, r_t) = r.split_at_mut(particles);
    // Starts first, then ends: along a chain an edge's end is the next one's start,
    // and in one loop each update would wait on the last one's store.
    for k in 0..m {
        let a = s.ends[first_edge + k].0 as usize;
        let d = 2.0 * s.inverse_mass[a] * s.edge[first_edge + k];
        r_n[a - first] += y[2 * k] * d;
        r_t[a - first] += y[2 * k + 1] * d;
    }
    for k in 0..m {
        let b = s.ends[first_edge + k].1 as usize;
        let d = 2.0 * s.inverse_mass[b] * s.edge[first_edge + k];
        r_n[b - first] -= y[2 * k] * d;
        r_t[b - first] -= y[2 * k + 1] * d;
    }
    for &(j, coefficient) in &row.entries[..row.count as usize] {
        if in_part(j) {
            let (local, w) = (j as usize - first, s.inverse_mass[j as usize] * coefficient);
            r_n[local] += w * normal;
            r_t[local] += w * tangent;
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

impl Sweeps {
    /// How far (a distance per step) the most violated normal row falls short at the
    /// current corrections.
    pub(super) fn violation(s: &JointScratch) -> f64 {
        s.rows
            .iter()
            .filter(|row| row.count > 0)
            .map(|row| -(row.slack_n + moved(&s.correction, row, row.normal)))
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
        s: &mut JointScratch,
        first: bool,
        cap: u32,
        tolerance: f64,
    ) -> u32 {
        s.correction.copy_from_slice(&s.base);
        for c in 0..s.rows.len() {
            let row = &mut s.rows[c];
            if first {
                (row.start_n, row.start_t) = (0.0, 0.0);
            } else {
                (row.start_n, row.start_t) = (row.mu_n, row.mu_t);
            }
            let (warm_n, warm_t) = (row.mu_n - row.start_n, row.mu_t - row.start_t);
            if warm_n != 0.0 || warm_t != 0.0 {
                if !row.ready {
                    row_responses(set, islands, s, c);
                }
                apply(s, c, warm_n, warm_t);
            }
        }
        let mut sweeps = 0;
        while sweeps < cap {
            sweeps += 1;
            let mut worst = 0.0f64;
            for c in 0..s.rows.len() {
                let row = &s.rows[c];
                if row.count == 0 {
                    continue;
                }
                let value = row.slack_n + moved(&s.correction, row, row.normal);
                if value >= 0.0 && row.mu_n == 0.0 && row.mu_t == 0.0 {
                    continue; // met with no impulse: nothing to do
                }
                worst = worst.max(-value);
                if !row.ready {
                    row_responses(set, islands, s, c);
                }
                let row = &s.rows[c];
                if row.diag_n <= 0.0 {
                    continue;
                }
                // Normal first, then the tangent as the normal change leaves it (the
                // two share one pass over the corrections).
                let mu_n = (row.mu_n - value / row.diag_n).max(0.0);
                let change_n = mu_n - row.mu_n;
                let mut change_t = 0.0;
                if row.friction > 0.0 && row.diag_t > 0.0 && (mu_n > 0.0 || row.mu_t != 0.0) {
                    let value = row.slack_t
                        + moved(&s.correction, row, row.normal.perp())
                        + change_n * row.cross;
                    let cone = row.friction * mu_n;
                    change_t = (row.mu_t - value / row.diag_t).clamp(-cone, cone) - row.mu_t;
                }
                let row = &mut s.rows[c];
                row.mu_n = mu_n;
                row.mu_t += change_t;
                apply(s, c, change_n, change_t);
            }
            if worst <= tolerance {
                break;
            }
        }
        multipliers(s);
        sweeps
    }
}

/// `Σ cᵢ d·Δᵢ` of `row` along `d` for the corrections `correction`.
#[inline]
fn moved(correction: &[DVec2], row: &JointRow, d: DVec2) -> f64 {
    row.entries[..row.count as usize]
        .iter()
        .map(|&(j, coefficient)| coefficient * d.dot(correction[j as usize]))
        .sum()
}

/// The particle responses of link `link` of row `c` along `along`: the part's first
/// joint particle and the responses.
fn particle_response(s: &JointScratch, c: usize, link: usize, along: Along) -> (usize, &[DVec2]) {
    let (part, offset, _) = s.rows[c].links[link];
    let (first, particles) = s.parts[part as usize].particles;
    let (first, particles) = (first as usize, particles as usize);
    let start = offset as usize
        + if along == Along::Tangent {
            particles
        } else {
            0
        };
    (first, &s.particle_responses[start..start + particles])
}

/// `Σ cᵢ d·rᵢ` over row `c`'s particles for its responses `r` along `along`: its own
/// stiffness with `d` the same direction, the cross term with the other.
fn stiffness(s: &JointScratch, c: usize, along: Along, d: DVec2) -> f64 {
    let row = &s.rows[c];
    let mut value = 0.0;
    for link in 0..row.link_count as usize {
        let (first, r) = particle_response(s, c, link, along);
        for &(j, coefficient) in &row.entries[..row.count as usize] {
            if let Some(r) = r.get((j as usize).wrapping_sub(first)) {
                value += coefficient * d.dot(*r);
            }
        }
    }
    value
}

/// Add `normal` and `tangent` of row `c`'s impulses to the corrections.
fn apply(s: &mut JointScratch, c: usize, normal: f64, tangent: f64) {
    if normal == 0.0 && tangent == 0.0 {
        return;
    }
    for link in 0..s.rows[c].link_count as usize {
        let (part, offset, _) = s.rows[c].links[link];
        let (first, particles) = s.parts[part as usize].particles;
        let (first, particles) = (first as usize, particles as usize);
        let offset = offset as usize;
        let (correction, r) = (
            &mut s.correction[first..first + particles],
            &s.particle_responses[offset..offset + 2 * particles],
        );
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

/// The edge multipliers of this Newton step's contact impulses, `Σ dμ y`, per joint
/// edge (for the edges' tensions).
fn multipliers(s: &mut JointScratch) {
    s.contact_multiplier.fill(0.0);
    for c in 0..s.rows.len() {
        let row = s.rows[c];
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
                let y = &s.responses[offset as usize..offset as usize + 2 * m];
                let x = &mut s.contact_multiplier[first_edge..first_edge + m];
                for (x, y) in x.iter_mut().zip(y.chunks_exact(2)) {
                    *x += amount * y[along];
                }
            }
        }
    }
}
