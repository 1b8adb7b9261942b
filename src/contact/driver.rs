//! Driving the contact projection of islands in contact: which islands and loose
//! particles the rows touch, their independent groups ([`ContactGroups`]), and each group
//! projected on its own — on several threads when there are enough rows. A group
//! reads and writes only its own particles (the rows' other particles are pinned or
//! driven), so the result is the same bit for bit whatever the thread count.

use std::ops::Range;

use bevy::math::DVec2;

use super::groups::{ContactGroups, NONE, RowSlots};
use super::projection::project_with_contacts;
use super::rows::{ContactRow, RowImpulse};
use super::scratch::ContactScratch;
use super::settings::{ContactOutcome, ContactSettings};
use super::split::CUT_ROWS;
use crate::constraints::islands::IslandSet;
use crate::constraints::projection::{Bodies, ProjectionOutcome};
use crate::metrics::IterationStats;
use crate::model::NO_ISLAND;
use crate::parallel::alongside;

/// Below this many rows a contact projection stays on one thread.
const PARALLEL_ROWS: usize = 512;

/// The buffers of contact projections, reused every step.
#[derive(Default, Debug)]
pub(super) struct GroupDriver {
    /// Islands, then loose particles, that the current rows touch (sorted).
    islands: Vec<u32>,
    loose: Vec<u32>,
    /// Which islands (then which particles) are taken, while collecting.
    marks: Vec<bool>,
    row_slots: Vec<RowSlots>,
    groups: ContactGroups,
    /// The first lane is the calling thread's.
    lanes: Vec<Lane>,
    /// The velocities before the lanes ran.
    before: Vec<DVec2>,
    /// Per island: how many more of its group's projections go to the contact Newton
    /// first (set when its sweeps fell short of a squeezed pair, see
    /// [`NEWTON_FIRST_PROJECTIONS`]).
    newton_first: Vec<u8>,
}

/// After a group's sweeps leave a squeezed pair short, its islands' next projections
/// go to the contact Newton first, this many of them: a landing or a pile at a game's
/// step stays squeezed for many steps, and the sweeps tried first each time were
/// three quarters of its cost (a profile of `pile_fine` at 1/60 s). Then the sweeps
/// are tried again.
const NEWTON_FIRST_PROJECTIONS: u8 = 8;

/// One thread's groups and buffers.
#[derive(Default, Debug)]
struct Lane {
    scratch: ContactScratch,
    groups: Range<u32>,
    velocity: Vec<DVec2>,
    members: Vec<u32>,
    loose: Vec<u32>,
    rows: Vec<ContactRow>,
    impulses: Vec<RowImpulse>,
    /// (row, its impulse) of every row the lane projected, in group order.
    taken: Vec<(u32, RowImpulse)>,
    /// (topology edge, impulse) of the lane's islands, in group order.
    edge_impulses: Vec<(u32, f64)>,
    outcomes: Vec<(u32, bool)>,
    stats: IterationStats,
    total: ContactOutcome,
    /// (island, escalated, went to the Newton first) of every member projected.
    newton_first: Vec<(u32, bool, bool)>,
}

/// What every group's projection reads.
struct Shared<'a> {
    set: &'a IslandSet,
    islands: &'a [u32],
    loose: &'a [u32],
    groups: &'a ContactGroups,
    rows: &'a [ContactRow],
    impulses: &'a [RowImpulse],
    dt: f64,
    settings: &'a ContactSettings,
    /// Per island, as [`GroupDriver::newton_first`].
    newton_first: &'a [u8],
}

impl GroupDriver {
    /// Room for `islands` islands and `particles` particles.
    pub(super) fn reserve(&mut self, islands: usize, particles: usize) {
        self.islands.reserve(islands);
        self.loose.reserve(particles);
        self.marks.resize(islands + particles, false);
        // A new numbering of the islands: what was remembered of the old one is dropped.
        self.newton_first.clear();
        self.newton_first.resize(islands, 0);
    }

    /// Project every island `rows` touch (`island` gives each particle's
    /// island) and the loose free particles they touch: each member's outcome into
    /// `outcomes`, its edges' impulses added to `edge_impulse`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn project(
        &mut self,
        set: &IslandSet,
        island: &[u32],
        bodies: &mut Bodies,
        rows: &[ContactRow],
        impulses: &mut [RowImpulse],
        dt: f64,
        settings: &ContactSettings,
        threads: usize,
        stats: &mut IterationStats,
        outcomes: &mut Vec<(u32, bool)>,
        edge_impulse: &mut [f64],
    ) -> ContactOutcome {
        outcomes.clear();
        self.collect(set.islands.len(), island, bodies, rows);
        if self.islands.is_empty() && self.loose.is_empty() {
            return ContactOutcome {
                converged: true,
                ..Default::default()
            };
        }
        self.group(island, rows);
        let groups = self.groups.count as u32;
        // A group with most of the rows, large enough to be cut, gets the threads inside
        // its own sweeps: the groups then run one after another.
        let largest = (0..groups).map(|g| self.groups.rows_of(g).len()).max();
        let dominant = largest.is_some_and(|r| r >= CUT_ROWS && 2 * r > rows.len());
        let lanes = if rows.len() < PARALLEL_ROWS || dominant {
            1
        } else {
            threads.clamp(1, groups.max(1) as usize)
        };
        self.split(lanes, rows.len());
        let inner = if lanes == 1 { threads } else { 1 };
        for lane in &mut self.lanes[..lanes] {
            lane.scratch.set_threads(inner);
        }
        if groups <= 1 {
            // One group: projected in place, as it comes.
            let lane = &mut self.lanes[0];
            lane.begin();
            let outcome = project_with_contacts(
                set,
                &self.islands,
                &self.loose,
                bodies.reborrow(),
                rows,
                impulses,
                dt,
                &with_memory(settings, &self.islands, &self.newton_first),
                &mut lane.scratch,
            );
            lane.account(set, &self.islands, &outcome);
        } else {
            let shared = Shared {
                set,
                islands: &self.islands,
                loose: &self.loose,
                groups: &self.groups,
                rows,
                impulses,
                dt,
                settings,
                newton_first: &self.newton_first,
            };
            Self::run_lanes(&mut self.lanes[..lanes], &mut self.before, &shared, bodies);
        }
        // A row that touches no member carries nothing.
        for (slot, &group) in impulses.iter_mut().zip(&self.groups.row_group) {
            if group == NONE {
                *slot = RowImpulse::default();
            }
        }
        let total = self.merge(lanes, impulses, edge_impulse, outcomes, stats);
        self.remember(lanes);
        total
    }

    /// Update each projected island's count of Newton-first projections: set where its
    /// group escalated, one fewer where it went to the Newton first.
    fn remember(&mut self, lanes: usize) {
        for lane in &self.lanes[..lanes] {
            for &(island, escalated, first) in &lane.newton_first {
                if let Some(count) = self.newton_first.get_mut(island as usize) {
                    if escalated {
                        *count = NEWTON_FIRST_PROJECTIONS;
                    } else if first {
                        *count = count.saturating_sub(1);
                    }
                }
            }
        }
    }

    /// Project each lane's groups, the first lane's on this thread and each other's on
    /// a thread of its own with its own copy of the velocities, then copy back what
    /// each changed (a particle is projected by one lane at most).
    fn run_lanes(
        lanes: &mut [Lane],
        before: &mut Vec<DVec2>,
        shared: &Shared,
        bodies: &mut Bodies,
    ) {
        let (first, rest) = lanes.split_at_mut(1);
        let first = &mut first[0];
        if rest.is_empty() {
            first.run(shared, bodies.reborrow());
        } else {
            let (position, inverse_mass) = (bodies.position, bodies.inverse_mass);
            before.clear();
            before.extend_from_slice(bodies.velocity);
            for lane in rest.iter_mut() {
                lane.velocity.clear();
                lane.velocity.extend_from_slice(bodies.velocity);
            }
            alongside(
                rest,
                |lane| {
                    let mut velocity = std::mem::take(&mut lane.velocity);
                    lane.run(shared, Bodies::new(position, &mut velocity, inverse_mass));
                    lane.velocity = velocity;
                },
                || first.run(shared, bodies.reborrow()),
            );
            // Each particle is projected by one lane at most: copy what the others changed.
            let bits = |v: &DVec2| v.to_array().map(f64::to_bits);
            for lane in rest.iter() {
                for ((v, own), before) in (bodies.velocity.iter_mut())
                    .zip(&lane.velocity)
                    .zip(before.iter())
                {
                    if bits(own) != bits(before) {
                        *v = *own;
                    }
                }
            }
        }
    }

    /// The lanes' results merged in group order: the same sums in the same order
    /// whatever the lanes.
    fn merge(
        &self,
        lanes: usize,
        impulses: &mut [RowImpulse],
        edge_impulse: &mut [f64],
        outcomes: &mut Vec<(u32, bool)>,
        stats: &mut IterationStats,
    ) -> ContactOutcome {
        let mut total = ContactOutcome {
            converged: true,
            ..Default::default()
        };
        for lane in &self.lanes[..lanes] {
            for &(c, impulse) in &lane.taken {
                if let Some(slot) = impulses.get_mut(c as usize) {
                    *slot = impulse;
                }
            }
            for &(edge, j) in &lane.edge_impulses {
                if let Some(slot) = edge_impulse.get_mut(edge as usize) {
                    *slot += j;
                }
            }
            outcomes.extend_from_slice(&lane.outcomes);
            stats.merge(&lane.stats);
            total.iterations = total.iterations.max(lane.total.iterations);
            total.sweeps += lane.total.sweeps;
            total.converged &= lane.total.converged;
            total.residual = total.residual.max(lane.total.residual);
            total.contact_violation = total.contact_violation.max(lane.total.contact_violation);
        }
        total
    }

    /// The islands, then the loose free particles, that `rows` touch, each once.
    fn collect(&mut self, islands: usize, island: &[u32], bodies: &Bodies, rows: &[ContactRow]) {
        self.islands.clear();
        self.loose.clear();
        self.marks.resize(islands + island.len(), false);
        for row in rows {
            for &p in &row.particles {
                let (slot, list, id) = match island_of(island, p as usize) {
                    Some(i) => (i, &mut self.islands, i as u32),
                    None if bodies.inverse_mass[p as usize] > 0.0 => {
                        (islands + p as usize, &mut self.loose, p)
                    }
                    None => continue,
                };
                if !self.marks[slot] {
                    self.marks[slot] = true;
                    list.push(id);
                }
            }
        }
        for &i in &self.islands {
            self.marks[i as usize] = false;
        }
        for &p in &self.loose {
            self.marks[islands + p as usize] = false;
        }
        self.islands.sort_unstable();
        self.loose.sort_unstable();
    }

    /// Group the members (the islands, then the loose particles, by position) as
    /// `rows` join them.
    fn group(&mut self, island: &[u32], rows: &[ContactRow]) {
        let (members, loose) = (&self.islands, &self.loose);
        let slot = |p: u32| -> u32 {
            let found = match island_of(island, p as usize) {
                Some(i) => members.binary_search(&(i as u32)).ok(),
                None => loose.binary_search(&p).ok().map(|k| members.len() + k),
            };
            found.map_or(NONE, |k| k as u32)
        };
        self.row_slots.clear();
        (self.row_slots).extend(rows.iter().map(|row| row.particles.map(slot)));
        self.groups
            .partition(members.len() + loose.len(), &self.row_slots);
    }

    /// Give `lanes` lanes contiguous runs of groups of about equal rows.
    fn split(&mut self, lanes: usize, rows: usize) {
        if self.lanes.len() < lanes {
            self.lanes.resize_with(lanes, Lane::default);
        }
        let mut start = 0u32;
        let mut seen = 0usize;
        for (k, lane) in self.lanes[..lanes].iter_mut().enumerate() {
            let mut end = start;
            let share = rows * (k + 1) / lanes;
            while (end as usize) < self.groups.count && (seen < share || k + 1 == lanes) {
                seen += self.groups.rows_of(end).len();
                end += 1;
            }
            lane.groups = start..end;
            start = end;
        }
    }
}

impl Lane {
    /// Project this lane's groups one after another.
    fn run(&mut self, shared: &Shared, mut bodies: Bodies) {
        self.begin();
        let ni = shared.islands.len();
        for g in self.groups.clone() {
            self.members.clear();
            self.loose.clear();
            // Slots ascend: the islands (by id), then the loose particles (by index).
            for &slot in shared.groups.slots_of(g) {
                match (slot as usize).checked_sub(ni) {
                    None => self.members.push(shared.islands[slot as usize]),
                    Some(k) => self.loose.push(shared.loose[k]),
                }
            }
            self.rows.clear();
            self.impulses.clear();
            let first_taken = self.taken.len();
            for &c in shared.groups.rows_of(g) {
                self.rows.push(shared.rows[c as usize]);
                (self.impulses).push(shared.impulses.get(c as usize).copied().unwrap_or_default());
                self.taken.push((c, RowImpulse::default()));
            }
            let outcome = project_with_contacts(
                shared.set,
                &self.members,
                &self.loose,
                bodies.reborrow(),
                &self.rows,
                &mut self.impulses,
                shared.dt,
                &with_memory(shared.settings, &self.members, shared.newton_first),
                &mut self.scratch,
            );
            for (taken, &impulse) in self.taken[first_taken..].iter_mut().zip(&self.impulses) {
                taken.1 = impulse;
            }
            let members = std::mem::take(&mut self.members);
            self.account(shared.set, &members, &outcome);
            self.members = members;
        }
    }

    /// Empty the lane's results.
    fn begin(&mut self) {
        self.taken.clear();
        self.edge_impulses.clear();
        self.outcomes.clear();
        self.newton_first.clear();
        self.stats = IterationStats::default();
        self.total = ContactOutcome {
            converged: true,
            ..Default::default()
        };
    }

    /// Keep the results of a projection of `members` (still in the scratch).
    fn account(&mut self, set: &IslandSet, members: &[u32], outcome: &ContactOutcome) {
        for (i, &member) in members.iter().enumerate() {
            self.outcomes.push((member, self.scratch.island_met(i)));
            if outcome.escalated || outcome.newton_first {
                (self.newton_first).push((member, outcome.escalated, outcome.newton_first));
            }
            let edges = &set.edges[set.islands[member as usize].edges.clone()];
            for (e, &j) in edges.iter().zip(self.scratch.edge_impulses(i)) {
                self.edge_impulses.push((e.edge, j));
            }
        }
        self.stats.record(&ProjectionOutcome {
            iterations: outcome.iterations,
            converged: outcome.converged,
            residual: outcome.residual,
            ..Default::default()
        });
        self.stats.record_factorizations(outcome.factorizations);
        self.stats.escalated += u64::from(outcome.escalated);
        self.total.iterations = self.total.iterations.max(outcome.iterations);
        self.total.sweeps += outcome.sweeps;
        self.total.converged &= outcome.converged;
        self.total.residual = self.total.residual.max(outcome.residual);
        self.total.contact_violation =
            (self.total.contact_violation).max(outcome.contact_violation);
    }
}

/// `settings` for a group of `members`: the Newton first if any member's count
/// ([`GroupDriver::newton_first`]) is left.
fn with_memory(settings: &ContactSettings, members: &[u32], counts: &[u8]) -> ContactSettings {
    ContactSettings {
        newton_first: members
            .iter()
            .any(|&m| counts.get(m as usize).is_some_and(|&c| c > 0)),
        ..*settings
    }
}

/// The island of `particle`, if it is in one.
fn island_of(island: &[u32], particle: usize) -> Option<usize> {
    island
        .get(particle)
        .copied()
        .filter(|&i| i != NO_ISLAND)
        .map(|i| i as usize)
}
