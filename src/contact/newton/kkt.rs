//! The contact Newton's linear system over a contact projection's particles and edges.
//!
//! Unknowns: each free particle's correction (x, y) and each edge's multiplier. The
//! matrix is `[H Jᵀ; J 0]`: H the masses plus the stiffness of the contact rows the
//! model holds (normal rows pressed, friction rows sticking), J the edges' unit
//! directions. A row couples only its own three particles, and an edge its two ends:
//! whatever the strands' lengths, the system is as sparse as the contacts themselves.
//!
//! The particles are ordered by geometric nested dissection (`ordering`), each edge's
//! multiplier right after the later of its two particles, so the sparse LDLᵀ
//! (`linalg::symbolic`) needs no pivoting. The pattern holds every row of the projection, pressed
//! or not, and is analysed once per projection (and kept while the next projection asks
//! for the same pattern); each Newton step only refills values.

use bevy::math::DVec2;

use crate::contact::local_row::LocalRow;
use crate::linalg::SingularPivot;
use crate::linalg::supernodal::{SupernodalFactor, SupernodalPlan};
use crate::linalg::symbolic::LdlPattern;

/// Not an unknown (a fixed particle, a locked edge).
pub(super) const NONE: u32 = u32::MAX;

/// What the system is built from: the contact projection's particles, edges and rows.
#[derive(Clone, Copy)]
pub(super) struct KktInput<'a> {
    pub(super) inverse_mass: &'a [f64],
    pub(super) ends: &'a [(u32, u32)],
    pub(super) locked: &'a [bool],
    pub(super) incident: &'a [(u32, f64)],
    pub(super) incident_start: &'a [u32],
    pub(super) rows: &'a [LocalRow],
    /// Which rows the system may press: the others have no room in its pattern.
    pub(super) included: &'a [bool],
}

/// The stiffness the model gives a row, a symmetric 2 × 2 matrix in the row's normal
/// and tangent (zero: the model leaves the row out of the matrix).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct RowModel {
    pub(super) nn: f64,
    pub(super) nt: f64,
    pub(super) tt: f64,
}

impl RowModel {
    /// Whether the model holds the row at all.
    pub(super) fn is_empty(&self) -> bool {
        *self == RowModel::default()
    }
}

/// The numbering, pattern, values and factor of the system, reused.
#[derive(Clone, Debug, Default)]
pub(super) struct Kkt {
    /// Threads the factorization may use (the contact projection's own).
    pub(super) threads: usize,
    /// Each local particle's x unknown (y follows), or [`NONE`] when it is fixed.
    pub(super) particle_unknown: Vec<u32>,
    /// Each local edge's unknown, or [`NONE`] when it is locked.
    pub(super) edge_unknown: Vec<u32>,
    negative: Vec<bool>,
    scale: Vec<f64>,
    /// The free local particles, and each local particle's index among them.
    free: Vec<u32>,
    compact: Vec<u32>,
    graph_start: Vec<u32>,
    graph_neighbour: Vec<u32>,
    /// The graph the particles were last ordered for (with its diagonal), the graph
    /// of this call in the same form, and the order.
    ordered_start: Vec<i32>,
    ordered_neighbour: Vec<i32>,
    asked_start: Vec<i32>,
    asked_neighbour: Vec<i32>,
    order: Vec<u32>,
    pairs: Vec<(u32, u32)>,
    fill: Vec<u32>,
    /// Each contribution's (column, row) in generation order, and its value slot.
    contribution: Vec<(u32, u32)>,
    slot: Vec<u32>,
    /// Where each row's pair contributions start (four per pair of its particles).
    row_first: Vec<u32>,
    /// Where the edges' curvature couplings start (two per edge with two free ends).
    curvature_first: u32,
    pattern: LdlPattern,
    /// The pattern (`start`, `row`) the analysis and plan were last made for.
    analyzed_start: Vec<u32>,
    analyzed_row: Vec<u32>,
    flag: Vec<u32>,
    value: Vec<f64>,
    plan: SupernodalPlan,
    factor: SupernodalFactor,
    /// Factorizations since the last [`Kkt::number`].
    pub(super) factorizations: u32,
}

impl Kkt {
    /// Unknowns of the system.
    pub(super) fn unknowns(&self) -> usize {
        self.pattern.len()
    }

    /// Number the unknowns of `input` and analyse the pattern.
    pub(super) fn number(&mut self, input: &KktInput) {
        let n = input.inverse_mass.len();
        self.free.clear();
        self.compact.clear();
        self.compact.resize(n, NONE);
        for (j, &w) in input.inverse_mass.iter().enumerate() {
            if w > 0.0 {
                self.compact[j] = self.free.len() as u32;
                self.free.push(j as u32);
            }
        }
        self.graph(input);
        self.order_particles();
        self.assign(input);
        self.contributions(input);
        // A contact set that holds from one projection to the next (a strand resting on
        // the floor) asks for the same pattern: its analysis and plan are kept.
        if self.pattern.start != self.analyzed_start || self.pattern.row != self.analyzed_row {
            self.pattern.analyze(&mut self.flag);
            self.plan.plan(&self.pattern);
            self.analyzed_start.clone_from(&self.pattern.start);
            self.analyzed_row.clone_from(&self.pattern.row);
        }
    }

    /// The particles' elimination order: approximate minimum degree (Amestoy, Davis
    /// and Duff), half the fill a geometric nested dissection left on a dropped pile's
    /// groups. The ordering allocates, so the last graph's order is kept and reused
    /// while the graph is the same (a resting contact's from step to step). The graph
    /// is symmetric and sorted, as the ordering asks; on the one
    /// error it reports (a malformed graph), the particles keep their order.
    fn order_particles(&mut self) {
        let m = self.free.len();
        // The ordering is given every diagonal entry: it skips them, and without them a
        // graph with fewer entries than particles underflows a check of the ordering's
        // own in a debug build.
        self.asked_start.clear();
        self.asked_neighbour.clear();
        self.asked_start.push(0);
        for i in 0..m {
            let row = &self.graph_neighbour
                [self.graph_start[i] as usize..self.graph_start[i + 1] as usize];
            let below = row.partition_point(|&j| (j as usize) < i);
            (self.asked_neighbour).extend(row[..below].iter().map(|&j| j as i32));
            self.asked_neighbour.push(i as i32);
            (self.asked_neighbour).extend(row[below..].iter().map(|&j| j as i32));
            self.asked_start.push(self.asked_neighbour.len() as i32);
        }
        if self.asked_start == self.ordered_start && self.asked_neighbour == self.ordered_neighbour
        {
            return;
        }
        std::mem::swap(&mut self.asked_start, &mut self.ordered_start);
        std::mem::swap(&mut self.asked_neighbour, &mut self.ordered_neighbour);
        self.order.clear();
        let control = amd::Control::default();
        match amd::order::<i32>(
            m as i32,
            &self.ordered_start,
            &self.ordered_neighbour,
            &control,
        ) {
            Ok((p, _, _)) => self.order.extend(p.iter().map(|&x| x as u32)),
            Err(_) => self.order.extend(0..m as u32),
        }
    }

    /// The free particles' graph: strand neighbours and particles that share a row.
    fn graph(&mut self, input: &KktInput) {
        let m = self.free.len();
        let compact = &self.compact;
        let pairs = &mut self.pairs;
        pairs.clear();
        for (k, &(a, b)) in input.ends.iter().enumerate() {
            let (a, b) = (compact[a as usize], compact[b as usize]);
            if !input.locked[k] && a != NONE && b != NONE {
                pairs.push((a, b));
            }
        }
        for (row, _) in input.rows.iter().zip(input.included).filter(|(_, i)| **i) {
            let entries = &row.entries[..row.count as usize];
            for (x, &(i, _)) in entries.iter().enumerate() {
                for &(j, _) in &entries[x + 1..] {
                    let (i, j) = (compact[i as usize], compact[j as usize]);
                    if i != NONE && j != NONE && i != j {
                        pairs.push((i, j));
                    }
                }
            }
        }
        self.graph_start.clear();
        self.graph_start.resize(m + 1, 0);
        for &(a, b) in pairs.iter() {
            self.graph_start[a as usize + 1] += 1;
            self.graph_start[b as usize + 1] += 1;
        }
        for i in 0..m {
            self.graph_start[i + 1] += self.graph_start[i];
        }
        self.graph_neighbour.clear();
        self.graph_neighbour.resize(2 * pairs.len(), 0);
        let fill = &mut self.fill;
        fill.clear();
        fill.extend_from_slice(&self.graph_start[..m]);
        for &(a, b) in pairs.iter() {
            self.graph_neighbour[fill[a as usize] as usize] = b;
            fill[a as usize] += 1;
            self.graph_neighbour[fill[b as usize] as usize] = a;
            fill[b as usize] += 1;
        }
        // Each neighbour once, in order (rows that share particles repeat pairs).
        let mut kept = 0;
        for i in 0..m {
            let (first, end) = (
                self.graph_start[i] as usize,
                self.graph_start[i + 1] as usize,
            );
            self.graph_neighbour[first..end].sort_unstable();
            self.graph_start[i] = kept as u32;
            for k in first..end {
                if k == first || self.graph_neighbour[k] != self.graph_neighbour[k - 1] {
                    self.graph_neighbour[kept] = self.graph_neighbour[k];
                    kept += 1;
                }
            }
        }
        self.graph_start[m] = kept as u32;
        self.graph_neighbour.truncate(kept);
    }

    /// Unknowns in elimination order: each particle's two, then every edge both of
    /// whose free ends now have theirs.
    fn assign(&mut self, input: &KktInput) {
        self.particle_unknown.clear();
        self.particle_unknown.resize(input.inverse_mass.len(), NONE);
        self.edge_unknown.clear();
        self.edge_unknown.resize(input.ends.len(), NONE);
        self.negative.clear();
        self.scale.clear();
        let mut next = 0u32;
        for &c in &self.order {
            let j = self.free[c as usize] as usize;
            self.particle_unknown[j] = next;
            next += 2;
            let mass = 1.0 / input.inverse_mass[j];
            self.negative.extend([false, false]);
            self.scale.extend([mass, mass]);
            let range = input.incident_start[j] as usize..input.incident_start[j + 1] as usize;
            for &(k, _) in &input.incident[range] {
                let k = k as usize;
                if input.locked[k] || self.edge_unknown[k] != NONE {
                    continue;
                }
                let (a, b) = input.ends[k];
                let other = if a as usize == j { b } else { a } as usize;
                if input.inverse_mass[other] == 0.0 || self.particle_unknown[other] != NONE {
                    self.edge_unknown[k] = next;
                    next += 1;
                    self.negative.push(true);
                    self.scale
                        .push(input.inverse_mass[a as usize] + input.inverse_mass[b as usize]);
                }
            }
        }
    }

    /// Every (column, row) the matrix fills, in the order [`Kkt::assemble_and_factor`] writes
    /// them, and the pattern they make (duplicates are summed by the factorization).
    fn contributions(&mut self, input: &KktInput) {
        let c = &mut self.contribution;
        c.clear();
        let entry = |p: u32, q: u32| (p.max(q), p.min(q));
        for &j in &self.free {
            let u = self.particle_unknown[j as usize];
            c.extend([entry(u, u), entry(u, u + 1), entry(u + 1, u + 1)]);
        }
        self.row_first.clear();
        for (row, &included) in input.rows.iter().zip(input.included) {
            self.row_first.push(c.len() as u32);
            if !included {
                continue;
            }
            let entries = &row.entries[..row.count as usize];
            for (x, &(i, _)) in entries.iter().enumerate() {
                for &(j, _) in &entries[x + 1..] {
                    let (u, v) = (
                        self.particle_unknown[i as usize],
                        self.particle_unknown[j as usize],
                    );
                    if u != NONE && v != NONE && u != v {
                        c.extend([
                            entry(u, v),
                            entry(u, v + 1),
                            entry(u + 1, v),
                            entry(u + 1, v + 1),
                        ]);
                    }
                }
            }
        }
        self.row_first.push(c.len() as u32);
        for (k, &(a, b)) in input.ends.iter().enumerate() {
            let e = self.edge_unknown[k];
            if e == NONE {
                continue;
            }
            for end in [a, b] {
                let u = self.particle_unknown[end as usize];
                if u != NONE {
                    c.extend([entry(u, e), entry(u + 1, e)]);
                }
            }
        }
        // The tensions' curvature couples an edge's two free ends, x with x, y with y.
        self.curvature_first = c.len() as u32;
        for (k, &(a, b)) in input.ends.iter().enumerate() {
            let (u, v) = (
                self.particle_unknown[a as usize],
                self.particle_unknown[b as usize],
            );
            if self.edge_unknown[k] != NONE && u != NONE && v != NONE {
                c.extend([entry(u, v), entry(u + 1, v + 1)]);
            }
        }
        // Counting sort by column.
        let n = self.negative.len();
        let p = &mut self.pattern;
        p.start.clear();
        p.start.resize(n + 1, 0);
        for &(col, _) in c.iter() {
            p.start[col as usize + 1] += 1;
        }
        for k in 0..n {
            p.start[k + 1] += p.start[k];
        }
        p.row.clear();
        p.row.resize(c.len(), 0);
        self.slot.clear();
        self.slot.resize(c.len(), 0);
        let fill = &mut self.fill;
        fill.clear();
        fill.extend_from_slice(&p.start[..n]);
        for (s, &(col, row)) in self.slot.iter_mut().zip(c.iter()) {
            let at = fill[col as usize];
            fill[col as usize] += 1;
            p.row[at as usize] = row;
            *s = at;
        }
        self.value.clear();
        self.value.resize(c.len(), 0.0);
    }

    /// Fill the values for the row models `model` at the edges `edge`, each edge's
    /// curvature `curvature[k]` (its tension over its length: the Lagrangian's second
    /// derivative along the edge's ends), and factor.
    pub(super) fn assemble_and_factor(
        &mut self,
        input: &KktInput,
        model: &[RowModel],
        edge: &[DVec2],
        curvature: &[f64],
    ) -> Result<(), SingularPivot> {
        self.value.fill(0.0);
        let mut at = 0usize;
        let (slot, value) = (&self.slot, &mut self.value);
        let mut add = |at: usize, v: f64| value[slot[at] as usize] += v;
        // Particles' own blocks: the mass, and each modelled row's stiffness on them.
        for &j in &self.free {
            let m = 1.0 / input.inverse_mass[j as usize];
            add(at, m);
            add(at + 2, m);
            at += 3;
        }
        let compact = &self.compact;
        let block_of = |j: u32| -> usize { 3 * compact[j as usize] as usize };
        for (r, (row, model)) in input.rows.iter().zip(model).enumerate() {
            if model.is_empty() || !input.included[r] {
                continue;
            }
            let (n, t) = (row.normal, row.normal.perp());
            // The 2 × 2 block of unit coefficients: [n t] A [n t]ᵀ.
            let xx = model.nn * n.x * n.x + 2.0 * model.nt * n.x * t.x + model.tt * t.x * t.x;
            let xy =
                model.nn * n.x * n.y + model.nt * (n.x * t.y + t.x * n.y) + model.tt * t.x * t.y;
            let yy = model.nn * n.y * n.y + 2.0 * model.nt * n.y * t.y + model.tt * t.y * t.y;
            let entries = &row.entries[..row.count as usize];
            for &(i, ci) in entries {
                if compact[i as usize] == NONE {
                    continue;
                }
                let b = block_of(i);
                let c2 = ci * ci;
                add(b, c2 * xx);
                add(b + 1, c2 * xy);
                add(b + 2, c2 * yy);
            }
            let mut pair = self.row_first[r] as usize;
            for (x, &(i, ci)) in entries.iter().enumerate() {
                for &(j, cj) in &entries[x + 1..] {
                    let (u, v) = (
                        self.particle_unknown[i as usize],
                        self.particle_unknown[j as usize],
                    );
                    if u != NONE && v != NONE && u != v {
                        let c = ci * cj;
                        add(pair, c * xx);
                        add(pair + 1, c * xy);
                        add(pair + 2, c * xy);
                        add(pair + 3, c * yy);
                        pair += 4;
                    }
                }
            }
        }
        at = self.row_first.last().copied().unwrap_or(at as u32) as usize;
        for (k, &(a, b)) in input.ends.iter().enumerate() {
            if self.edge_unknown[k] == NONE {
                continue;
            }
            let d = edge[k].normalize_or_zero();
            for (end, sign) in [(a, -1.0), (b, 1.0)] {
                if self.particle_unknown[end as usize] != NONE {
                    add(at, sign * d.x);
                    add(at + 1, sign * d.y);
                    at += 2;
                }
            }
        }
        let mut at = self.curvature_first as usize;
        for (k, &(a, b)) in input.ends.iter().enumerate() {
            if self.edge_unknown[k] == NONE || curvature[k] == 0.0 {
                if self.edge_unknown[k] != NONE
                    && compact[a as usize] != NONE
                    && compact[b as usize] != NONE
                {
                    at += 2;
                }
                continue;
            }
            let c = curvature[k];
            let (ca, cb) = (compact[a as usize], compact[b as usize]);
            for end in [ca, cb] {
                if end != NONE {
                    add(3 * end as usize, c);
                    add(3 * end as usize + 2, c);
                }
            }
            if ca != NONE && cb != NONE {
                add(at, -c);
                add(at + 1, -c);
                at += 2;
            }
        }
        self.factorizations += 1;
        self.factor.factor(
            &self.plan,
            &self.value,
            &self.scale,
            &self.negative,
            self.threads,
        )
    }

    /// Solve the last factored system for `x` in place.
    pub(super) fn solve(&self, x: &mut [f64]) {
        self.factor.solve(&self.plan, x);
    }

    /// The factorization's work (Σ of the factor's column counts squared) for the last
    /// analysed pattern.
    pub(super) fn work(&self) -> f64 {
        self.pattern.work()
    }
}
