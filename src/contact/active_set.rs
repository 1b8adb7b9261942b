//! Active rows: the speculative contact solve projects the rows that can act — those
//! warm-started from the last step and those within a margin of their target at the
//! start — with their neighbours (every row touching an island they join, whose other
//! side joins it too) and every row that joins nothing new. A row left out that the
//! projection leaves short is taken in, and the projection run again from the same
//! start, warm-started with what it found.
//!
//! Every pair within reach is a row, but most never push: the fur's neighbouring
//! hairs lie within reach of each other near their roots every step, well clear of
//! their cushion. Handed to the contact projection, such rows joined every island they
//! touch into one group, set up and swept every Newton step, for nothing. Left out, a
//! row clear of its target at the start is checked after the projection instead (in
//! the limp fur's first second, traced, none was then short: one round every step).

use bevy::math::DVec2;

use super::driver::GroupDriver;
use super::rows::{ContactRow, RowImpulse};
use super::settings::{ContactOutcome, ContactSettings};
use crate::constraints::islands::IslandSet;
use crate::constraints::projection::Bodies;
use crate::metrics::IterationStats;
use crate::model::NO_ISLAND;
use crate::model::union_find::UnionFind;

/// Projections of one call at most: the last keeps the rows it has, and what it
/// leaves short is the collision stage's, as for rows the sweeps do not meet.
const MAX_ROUNDS: usize = 4;

/// The buffers of [`ActiveRows::project`], reused every step.
#[derive(Default, Debug)]
pub(super) struct ActiveRows {
    live: Vec<bool>,
    /// The members (islands, then loose particles by index) the live rows join.
    sets: UnionFind,
    /// Whether each set's root has a live row.
    acting: Vec<bool>,
    /// Rows to take in next.
    next: Vec<u32>,
    /// Each projected row's index among all the rows.
    index: Vec<u32>,
    rows: Vec<ContactRow>,
    impulses: Vec<RowImpulse>,
    /// The velocities and edge impulses before the first round.
    velocity: Vec<DVec2>,
    edge_impulse: Vec<f64>,
}

/// How far (a distance over the step) `row` falls short of its target at `velocity`.
fn shortfall(row: &ContactRow, velocity: &[DVec2], dt: f64) -> f64 {
    (row.target - row.normal_velocity(velocity)) * dt
}

/// A row's members: the slot of each particle's island, or of the particle itself
/// when it is free and in no island (`None`: a fixed particle, no member).
fn slots(
    row: &ContactRow,
    islands: usize,
    island: &[u32],
    inverse_mass: &[f64],
) -> [Option<usize>; 3] {
    row.particles.map(|p| {
        let p = p as usize;
        match island.get(p).copied().filter(|&i| i != NO_ISLAND) {
            Some(i) => Some(i as usize),
            None => (inverse_mass[p] > 0.0).then_some(islands + p),
        }
    })
}

/// Join a live row's members into one acting set.
fn join(sets: &mut UnionFind, acting: &mut [bool], members: [Option<usize>; 3]) {
    if let Some(first) = sets.union_all(members.into_iter().flatten()) {
        acting[first] = true;
    }
}

/// Move every acting mark to its set's root.
fn settle_roots(sets: &mut UnionFind, acting: &mut [bool]) {
    for slot in 0..acting.len() {
        if acting[slot] {
            acting[sets.find(slot)] = true;
        }
    }
}

impl ActiveRows {
    /// Mark live the rows next to the acting ones: every row with a member that the
    /// live rows join (its other members join their group: they are what the group's
    /// motion pushes first), then every row whose members are all in one such group
    /// (it joins nothing new).
    fn take_in_neighbours(
        &mut self,
        islands: usize,
        island: &[u32],
        inverse_mass: &[f64],
        rows: &[ContactRow],
    ) {
        let slots_of = |row: &ContactRow| slots(row, islands, island, inverse_mass);
        self.sets.reset(islands + island.len());
        self.acting.clear();
        self.acting.resize(islands + island.len(), false);
        for (row, _) in rows.iter().zip(&self.live).filter(|(_, l)| **l) {
            join(&mut self.sets, &mut self.acting, slots_of(row));
        }
        settle_roots(&mut self.sets, &mut self.acting);
        // The neighbours, judged against the groups of the live rows alone.
        self.next.clear();
        for (c, row) in rows.iter().enumerate() {
            if !self.live[c]
                && slots_of(row)
                    .into_iter()
                    .flatten()
                    .any(|s| self.acting[self.sets.find(s)])
            {
                self.next.push(c as u32);
            }
        }
        for &c in &self.next {
            self.live[c as usize] = true;
            join(
                &mut self.sets,
                &mut self.acting,
                slots_of(&rows[c as usize]),
            );
        }
        settle_roots(&mut self.sets, &mut self.acting);
        for (row, live) in rows.iter().zip(self.live.iter_mut()) {
            if *live {
                continue;
            }
            let mut roots = slots_of(row)
                .into_iter()
                .flatten()
                .map(|s| self.sets.find(s));
            if let Some(first) = roots.next() {
                *live = self.acting[first] && roots.all(|r| r == first);
            }
        }
    }

    /// Mark live the rows that act from the start: warm-started, or clear of their
    /// target by less than `margin`, and their neighbours.
    #[allow(clippy::too_many_arguments)]
    fn mark_acting(
        &mut self,
        set: &IslandSet,
        island: &[u32],
        bodies: &Bodies,
        rows: &[ContactRow],
        impulses: &[RowImpulse],
        dt: f64,
        margin: f64,
    ) {
        self.live.clear();
        self.live.extend(rows.iter().enumerate().map(|(c, row)| {
            impulses.get(c).is_some_and(|i| *i != RowImpulse::default())
                || shortfall(row, bodies.velocity, dt) > -margin
        }));
        self.take_in_neighbours(set.islands.len(), island, bodies.inverse_mass, rows);
    }

    /// [`GroupDriver::project`] over the rows that act: `rows` and `impulses` as there
    /// (a row left out ends with no impulse); the islands projected are those the
    /// acting rows touch. A row acts from the start when it is warm-started or clear of
    /// its target by less than `margin` (a distance over the step); with no margin,
    /// every row acts.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn project(
        &mut self,
        driver: &mut GroupDriver,
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
        margin: Option<f64>,
    ) -> ContactOutcome {
        let every_row = match margin {
            None => true,
            Some(margin) => {
                self.mark_acting(set, island, bodies, rows, impulses, dt, margin);
                self.live.iter().all(|&l| l)
            }
        };
        if every_row {
            return driver.project(
                set,
                island,
                bodies,
                rows,
                impulses,
                dt,
                settings,
                threads,
                stats,
                outcomes,
                edge_impulse,
            );
        }
        self.velocity.clear();
        self.velocity.extend_from_slice(bodies.velocity);
        self.edge_impulse.clear();
        self.edge_impulse.extend_from_slice(edge_impulse);
        let mut round = 1;
        loop {
            if round > 1 {
                self.take_in_neighbours(set.islands.len(), island, bodies.inverse_mass, rows);
            }
            self.index.clear();
            self.rows.clear();
            self.impulses.clear();
            for (c, row) in rows.iter().enumerate() {
                if self.live[c] {
                    self.index.push(c as u32);
                    self.rows.push(*row);
                    self.impulses
                        .push(impulses.get(c).copied().unwrap_or_default());
                }
            }
            let mut outcome = driver.project(
                set,
                island,
                bodies,
                &self.rows,
                &mut self.impulses,
                dt,
                settings,
                threads,
                stats,
                outcomes,
                edge_impulse,
            );
            for (&c, &impulse) in self.index.iter().zip(&self.impulses) {
                if let Some(slot) = impulses.get_mut(c as usize) {
                    *slot = impulse;
                }
            }
            // The rows left out that this projection left short.
            let (mut added, mut worst) = (false, 0.0f64);
            for (c, row) in rows.iter().enumerate() {
                if self.live[c] {
                    continue;
                }
                let short = shortfall(row, bodies.velocity, dt);
                if short > settings.contact_tolerance {
                    worst = worst.max(short);
                    if round < MAX_ROUNDS {
                        self.live[c] = true;
                        added = true;
                    }
                }
            }
            if !added {
                outcome.contact_violation = outcome.contact_violation.max(worst);
                return outcome;
            }
            // Again from the same start, the rows found so far warm-started.
            bodies.velocity.copy_from_slice(&self.velocity);
            edge_impulse.copy_from_slice(&self.edge_impulse);
            round += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::islands::find_islands;
    use crate::constraints::projection::{ConstraintDirection, ProjectionSettings};
    use crate::model::{Edge, PointEdgePair};

    const DT: f64 = 0.01;
    const CUSHION: f64 = 0.05;
    const TOLERANCE: f64 = 1e-9;

    /// `strands` horizontal rods of length one, 0.1 above each other (the first on
    /// top), each one's first end over the middle of the one below; the top one falling
    /// at `speed`.
    struct Stack {
        position: Vec<DVec2>,
        velocity: Vec<DVec2>,
        inverse_mass: Vec<f64>,
        set: IslandSet,
        island: Vec<u32>,
        rows: Vec<ContactRow>,
    }

    impl Stack {
        fn new(strands: usize, speed: f64) -> Stack {
            let mut position = Vec::new();
            let mut edges = Vec::new();
            for s in 0..strands {
                let (x, y) = (
                    0.5 * (strands - 1 - s) as f64,
                    0.1 * (strands - 1 - s) as f64,
                );
                let first = position.len() as u32;
                position.extend([DVec2::new(x, y), DVec2::new(x + 1.0, y)]);
                edges.push(Edge::new(first, first + 1, 1.0));
            }
            let n = position.len();
            let set = find_islands(&edges, &vec![false; n]);
            let mut island = vec![NO_ISLAND; n];
            for (k, i) in set.islands.iter().enumerate() {
                for e in &set.edges[i.edges.clone()] {
                    island[e.a as usize] = k as u32;
                    island[e.b as usize] = k as u32;
                }
            }
            let mut velocity = vec![DVec2::ZERO; n];
            for v in &mut velocity[..2] {
                v.y = -speed;
            }
            let rows = (0..strands - 1)
                .map(|s| {
                    let (p, q) = (2 * s, 2 * (s + 1));
                    let pair = PointEdgePair {
                        p,
                        q,
                        r: q + 1,
                        alpha: 0.5,
                    };
                    let mut row = ContactRow::point_edge(pair, DVec2::Y, &velocity);
                    let gap = position[p].y - position[q].y;
                    row.target = (CUSHION - gap) / DT;
                    row
                })
                .collect();
            Stack {
                position,
                velocity,
                inverse_mass: vec![1.0; n],
                set,
                island,
                rows,
            }
        }

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
                solver: Default::default(),
                newton_first: false,
            }
        }

        /// Project with active rows (`margin`), or every row when `None`.
        fn project(&mut self, margin: Option<f64>) -> (Vec<RowImpulse>, Vec<(u32, bool)>) {
            let mut impulses = vec![RowImpulse::default(); self.rows.len()];
            let mut outcomes = Vec::new();
            let mut edge_impulse = vec![0.0; self.set.edges.len()];
            let mut driver = GroupDriver::default();
            driver.reserve(self.set.islands.len(), self.position.len());
            let mut bodies = Bodies::new(&self.position, &mut self.velocity, &self.inverse_mass);
            let mut stats = IterationStats::default();
            let (set, island, rows, settings) =
                (&self.set, &self.island, &self.rows, &Self::settings());
            let outcome = ActiveRows::default().project(
                &mut driver,
                set,
                island,
                &mut bodies,
                rows,
                &mut impulses,
                DT,
                settings,
                1,
                &mut stats,
                &mut outcomes,
                &mut edge_impulse,
                margin,
            );
            assert!(outcome.converged, "{outcome:?}");
            (impulses, outcomes)
        }

        fn worst_shortfall(&self) -> f64 {
            (self.rows.iter())
                .map(|row| shortfall(row, &self.velocity, DT))
                .fold(f64::NEG_INFINITY, f64::max)
        }

        fn max_relative_error(&self) -> f64 {
            let end = |i: u32| self.position[i as usize] + DT * self.velocity[i as usize];
            (self.set.edges.iter())
                .map(|e| (end(e.b).distance(end(e.a)) - e.rest_length).abs() / e.rest_length)
                .fold(0.0, f64::max)
        }
    }

    #[test]
    fn a_row_left_out_that_ends_short_is_taken_in_and_met() {
        // The top strand lands on the second, which the row between them pushes onto
        // the third; the row between the third and the fourth is clear at the start,
        // beyond the margin and no neighbour of the acting rows, so it is left out of
        // the first projection, which leaves it short.
        let mut active = Stack::new(4, 60.0);
        let momentum: DVec2 = active.velocity.iter().sum();
        let (impulses, outcomes) = active.project(Some(0.01));
        assert!(impulses.iter().all(|i| i.normal > 0.0), "{impulses:?}");
        assert_eq!(outcomes.len(), 4);
        assert!(
            active.worst_shortfall() <= TOLERANCE,
            "{}",
            active.worst_shortfall()
        );
        assert!(active.max_relative_error() < 1e-12);
        let after: DVec2 = active.velocity.iter().sum();
        assert!(
            (after - momentum).length() < 1e-9 * momentum.length(),
            "{after} {momentum}"
        );

        // The motion of projecting every row from the start, to a few millionths of
        // the speed (each solve stops its rows at its own iterate, to the tolerance).
        let mut every = Stack::new(4, 60.0);
        every.project(None);
        for (a, b) in active.velocity.iter().zip(&every.velocity) {
            assert!(a.distance(*b) < 1e-5 * 60.0, "{a} {b}");
        }
    }

    #[test]
    fn rows_clear_of_their_targets_leave_their_islands_alone() {
        // Nothing falls: every row is clear by twice the cushion, beyond the margin.
        let mut stack = Stack::new(3, 0.0);
        let before = stack.velocity.clone();
        let (impulses, outcomes) = stack.project(Some(0.01));
        assert!(outcomes.is_empty(), "{outcomes:?}");
        assert!(impulses.iter().all(|i| *i == RowImpulse::default()));
        assert_eq!(stack.velocity, before);
        // Within the margin, the same rows are projected (and push nothing).
        let (impulses, outcomes) = stack.project(Some(0.1));
        assert_eq!(outcomes.len(), 3);
        assert!(impulses.iter().all(|i| i.normal == 0.0), "{impulses:?}");
    }
}
