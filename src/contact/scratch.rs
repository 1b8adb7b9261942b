//! The contact projection's state: its parts, its rows in local terms and the buffers
//! both the Newton iterations (`projection`) and the rows' sweeps (`sweeps`) work on.

use bevy::math::DVec2;

use super::local_row::LocalRow;
use super::newton::scratch::NewtonScratch;
use super::split::RowCut;
use crate::constraints::projection::edge;
use crate::constraints::projection::scratch::{Factors, IslandScratch};

/// One part of the contact problem: an island, or a loose free particle (no edges).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Part {
    /// The island's position in the `islands` argument, or [`LOOSE`].
    pub(super) island: u32,
    /// First local particle and count.
    pub(super) particles: (u32, u32),
    /// First local edge and count.
    pub(super) edges: (u32, u32),
    pub(super) shortest: f64,
    pub(super) residual: f64,
    /// A linear solve met a singular system in some Newton step.
    pub(super) singular: bool,
    /// Whether its factor in `part_factors` is good (the latest Newton step's).
    pub(super) factored: bool,
    /// Its corrections were absurd and were not applied.
    pub(super) rejected: bool,
}

/// Marks a part that is a loose particle.
pub(super) const LOOSE: u32 = u32::MAX;

/// Not a particle of the contact problem.
pub(super) const NOT_LOCAL: u32 = u32::MAX;

/// Buffers of [`project_with_contacts`](super::project_with_contacts), reused from call to call.
#[derive(Clone, Debug, Default)]
pub struct ContactScratch {
    pub(super) parts: Vec<Part>,
    /// Packed index of each local particle.
    pub(super) packed: Vec<u32>,
    pub(super) inverse_mass: Vec<f64>,
    /// The correction Δ of each local particle.
    pub(super) correction: Vec<DVec2>,
    /// Δ at the start of the current Newton step.
    pub(super) step_start: Vec<DVec2>,
    /// Δ after the current Newton step's edge correction, before contacts.
    pub(super) base: Vec<DVec2>,
    /// Edges at each local particle: `(local edge, ±1)`, from `incident_start`.
    pub(super) incident: Vec<(u32, f64)>,
    pub(super) incident_start: Vec<u32>,
    /// Local ends of each local edge.
    pub(super) ends: Vec<(u32, u32)>,
    pub(super) rest_squared: Vec<f64>,
    pub(super) predicted_edge: Vec<DVec2>,
    pub(super) edge: Vec<DVec2>,
    pub(super) constraint: Vec<f64>,
    pub(super) locked: Vec<bool>,
    /// Edge multipliers of this Newton step's edge correction.
    pub(super) edge_multiplier: Vec<f64>,
    /// Contact multipliers `Σ dμ A⁻¹ J W f` of this Newton step, per local edge.
    pub(super) contact_multiplier: Vec<f64>,
    /// Each local edge's impulse over the projection (mass × length, tension positive).
    pub(super) edge_impulse: Vec<f64>,
    /// The packed → local particle map (free particles of the parts only).
    pub(super) local_of: Vec<u32>,
    /// The rows in sweep order (`cut.rows` gives each one's index in the caller's).
    pub(super) rows: Vec<LocalRow>,
    /// The response room of side 0's rows, side 1's and those between.
    pub(super) banks: [Bank; 3],
    /// The members' layout order and the rows' sweep order.
    pub(super) cut: RowCut,
    /// Each member's part.
    pub(super) part_of_member: Vec<u32>,
    /// The first local particle of side 1 (the particle count when the problem is not
    /// cut: every particle is then on side 0).
    pub(super) side_1: usize,
    /// Threads the sweeps may use (a cut problem's sides take two at most).
    pub(super) threads: usize,
    pub(super) island: IslandScratch,
    /// Each part's factor at the Newton step that last factored it.
    pub(super) part_factors: Vec<Factors>,
    /// Whether each part met its edges (by part), after the last call.
    pub(super) met: Vec<bool>,
    /// The contact Newton's buffers.
    pub(super) newton: NewtonScratch,
}

/// Room for the responses of one group of rows, taken as they first push.
#[derive(Clone, Debug, Default)]
pub(super) struct Bank {
    /// Room taken so far in this projection: particle responses, edge responses.
    pub(super) placed: (u32, u32),
    /// Responses in edge space, two per link (normal, tangent), `edges` values each.
    pub(super) responses: Vec<f64>,
    /// Responses per particle, two per link (normal, tangent), `particles` each.
    pub(super) particle_responses: Vec<DVec2>,
}

impl ContactScratch {
    /// The shortest rest length of the projection's edges (infinite with none).
    pub(super) fn shortest_edge(&self) -> f64 {
        (self.parts.iter())
            .map(|p| p.shortest)
            .fold(f64::INFINITY, f64::min)
    }

    /// Let the sweeps of a cut projection run its two sides at once when `threads` is
    /// more than one (the result is the same whatever the count).
    pub fn set_threads(&mut self, threads: usize) {
        self.threads = threads;
    }

    /// After [`project_with_contacts`](super::project_with_contacts): whether the island passed as `islands[i]` met its
    /// edges (and had its corrections applied).
    pub fn island_met(&self, i: usize) -> bool {
        let part = self.part_of_member.get(i).copied();
        part.and_then(|p| self.met.get(p as usize).copied())
            .unwrap_or(false)
    }

    /// After [`project_with_contacts`](super::project_with_contacts): the impulse each edge of the island passed as
    /// `islands[i]` carried (mass × length, tension positive), in the island's edge
    /// order.
    pub fn edge_impulses(&self, i: usize) -> &[f64] {
        let (first, count) = self.parts[self.part_of_member[i] as usize].edges;
        &self.edge_impulse[first as usize..(first + count) as usize]
    }
}

/// The largest change of an edge's span, `|motion(b) − motion(a)|` over the local edges
/// `ends`, in a Newton step that moves each local particle `j` by `motion(j)`: what
/// the step's linearization of that edge misses grows with it, while a strand carried
/// whole (a landing stopped in one step) is linear in it.
pub(super) fn longest_swing(ends: &[(u32, u32)], motion: impl Fn(usize) -> DVec2) -> f64 {
    (ends.iter())
        .map(|&(a, b)| (motion(b as usize) - motion(a as usize)).length())
        .fold(0.0f64, f64::max)
}

/// The trust region of a Newton step: no edge's span changes by more than half the
/// shortest edge of the projection (`trust`); the fraction of a step whose largest
/// change is `longest` that stays inside it.
pub(super) fn within_trust(longest: f64, trust: f64) -> f64 {
    if longest > trust {
        trust / longest
    } else {
        1.0
    }
}

/// The edges at the current corrections, their constraint values and each part's
/// residual; returns the largest.
pub(super) fn measure_edges(s: &mut ContactScratch) -> f64 {
    let mut largest = 0.0f64;
    for part in &mut s.parts {
        let (first, count) = (part.edges.0 as usize, part.edges.1 as usize);
        let mut residual = 0.0f64;
        for k in first..first + count {
            let (a, b) = s.ends[k];
            let (from, to) = (s.correction[a as usize], s.correction[b as usize]);
            (s.edge[k], s.constraint[k]) =
                edge::at(s.predicted_edge[k], from, to, s.rest_squared[k]);
            if !s.locked[k] {
                residual = residual.max(s.constraint[k].abs() / s.rest_squared[k]);
            }
        }
        part.residual = residual;
        largest = largest.max(residual);
    }
    largest
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_swing_counts_what_bends_an_edge_not_what_carries_it() {
        let ends = [(0, 1), (1, 2)];
        // Carried whole: no edge changes its span.
        assert_eq!(longest_swing(&ends, |_| DVec2::new(0.3, -2.0)), 0.0);
        // The middle particle pushed 1 mm sideways: both its edges change by 1 mm.
        let bend = |j: usize| {
            if j == 1 {
                DVec2::new(0.0, 1e-3)
            } else {
                DVec2::ZERO
            }
        };
        assert!((longest_swing(&ends, bend) - 1e-3).abs() < 1e-15);
        // An end spun about the middle: its edge changes by the difference.
        let spin = |j: usize| {
            if j == 2 {
                DVec2::new(-2e-3, 2e-3)
            } else {
                DVec2::ZERO
            }
        };
        assert!((longest_swing(&ends, spin) - 8e-6f64.sqrt()).abs() < 1e-15);
        assert_eq!(within_trust(4e-3, 2e-3), 0.5);
        assert_eq!(within_trust(1e-3, 2e-3), 1.0);
    }
}
