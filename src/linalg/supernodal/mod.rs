//! Supernodal multifrontal LDLᵀ of a symmetric quasi-definite matrix numbered in
//! elimination order: the contact Newton's linear solve.
//!
//! Columns whose factor columns share their structure (a particle's x and y, a chain
//! of separator unknowns) are factored together as one dense front: the front
//! gathers the matrix's columns and the update matrices its children left, factors
//! its pivot columns, and leaves its own update matrix for its parent (Duff and
//! Reid's multifrontal method). The work is the same as the column-by-column
//! factorization's, done in dense loops over contiguous memory, and the fronts are
//! visited children first, so their updates are a stack.
//!
//! Pivots are of one sign per unknown, as [`symbolic`](super::symbolic) explains; an edge whose
//! pivot vanishes is dropped (its multiplier is zero).

mod split;

use super::pivot::{Pivot, SingularPivot, quasi_definite};
use super::symbolic::LdlPattern;

/// No supernode.
const NONE: u32 = u32::MAX;

/// The supernodes of a pattern, their fronts' rows and the order they are factored in.
#[derive(Clone, Debug, Default)]
pub struct SupernodalPlan {
    /// Each supernode's first column and width, in the order they are factored (a
    /// postorder of the supernodal tree: children before parents).
    first: Vec<u32>,
    width: Vec<u32>,
    /// Each supernode's front rows: its own columns, then the rows below, ascending.
    rows_start: Vec<u32>,
    rows: Vec<u32>,
    /// Where each supernode's rows below its columns sit in its parent's front.
    relative: Vec<u32>,
    /// How many rows from each of those on land in consecutive parent rows: the
    /// extend-add adds a run as one slice.
    run: Vec<u32>,
    /// Each supernode's number of children (their updates are on the stack).
    children: Vec<u32>,
    /// Where each supernode's factor panel (front rows × width) starts.
    panel: Vec<usize>,
    /// The matrix's lower triangle by column: `(row, value slot)`.
    lower_start: Vec<u32>,
    lower: Vec<(u32, u32)>,
    /// The largest front, and the most the update stack holds.
    largest: usize,
    stack: usize,
    n: usize,
    count: Vec<u32>,
    /// Two sibling runs of subtrees to factor on two threads, if worth it.
    split: Option<split::Split>,
    work: PlanWork,
}

/// The planning's buffers.
#[derive(Clone, Debug, Default)]
struct PlanWork {
    children: Vec<u32>,
    node_of: Vec<u32>,
    node_start: Vec<u32>,
    below_start: Vec<u32>,
    below: Vec<u32>,
    mark: Vec<u32>,
    tree_parent: Vec<u32>,
    /// Each supernode's first child, and each supernode's next sibling.
    head: Vec<u32>,
    next: Vec<u32>,
    order: Vec<u32>,
    stack: Vec<(u32, u32)>,
    index_of: Vec<u32>,
    held: Vec<usize>,
    fill: Vec<u32>,
    /// Each supernode's first column after amalgamation, whether it still stands,
    /// and its panel's non-zeros.
    first_of: Vec<u32>,
    alive: Vec<bool>,
    nonzeros: Vec<usize>,
    /// Each supernode's subtree's work and first supernode, in factor order.
    subtree: Vec<f64>,
    subtree_start: Vec<u32>,
}

/// The numeric factor and the buffers that make it.
#[derive(Clone, Debug, Default)]
pub struct SupernodalFactor {
    /// Each supernode's panel, column by column (unit diagonal not stored).
    panels: Vec<f64>,
    /// The pivots; an infinite one marks a dropped (dependent) unknown.
    pub diagonal: Vec<f64>,
    /// The fronts of the calling thread, and of the second when the plan is split.
    fronts: Fronts,
    second: Fronts,
    second_diagonal: Vec<f64>,
    /// Unknowns dropped as dependent in the last factorization.
    pub dropped: u32,
}

/// What factors a run of supernodes: the dense front, the update matrices waiting for
/// their parents (and whose each is), each row's place in the current front.
#[derive(Clone, Debug, Default)]
struct Fronts {
    front: Vec<f64>,
    updates: Vec<f64>,
    owners: Vec<u32>,
    position: Vec<u32>,
    dropped: u32,
}

/// The numeric inputs of a factorization.
#[derive(Clone, Copy)]
struct Values<'a> {
    value: &'a [f64],
    scale: &'a [f64],
    negative: &'a [bool],
}

impl SupernodalPlan {
    /// Plan the factorization of the analysed pattern `p`.
    pub fn new(p: &LdlPattern) -> SupernodalPlan {
        let mut plan = SupernodalPlan::default();
        plan.plan(p);
        plan
    }

    /// Plan again for the analysed pattern `p`, reusing the buffers (a steady pattern
    /// allocates nothing).
    pub fn plan(&mut self, p: &LdlPattern) {
        let n = p.len();
        self.n = n;
        p.column_counts_into(&mut self.count);
        let nodes = self.fundamental(p.parent());
        self.rows_below(p, nodes);
        self.amalgamate(nodes);
        self.lay_out(nodes);
        self.place_in_parents();
        self.split = split::choose(self);
    }

    /// Fundamental supernodes: column j joins j − 1 when j − 1's only parent is j, j
    /// has no other child, and their structures nest. Returns how many.
    fn fundamental(&mut self, parent: &[u32]) -> usize {
        let n = self.n;
        let w = &mut self.work;
        w.children.clear();
        w.children.resize(n, 0);
        for &q in parent {
            if q != NONE {
                w.children[q as usize] += 1;
            }
        }
        w.node_of.clear();
        w.node_start.clear();
        for j in 0..n {
            let joins = j > 0
                && parent[j - 1] == j as u32
                && w.children[j] == 1
                && self.count[j - 1] == self.count[j] + 1;
            if !joins {
                w.node_start.push(j as u32);
            }
            w.node_of.push(w.node_start.len() as u32 - 1);
        }
        let nodes = w.node_start.len();
        w.node_start.push(n as u32);
        nodes
    }

    /// Each supernode's rows below its columns (the matrix's, then its children's) and
    /// its parent in the supernodal tree.
    fn rows_below(&mut self, p: &LdlPattern, nodes: usize) {
        // Each supernode's rows below its columns: the matrix's, then its children's
        // (children come first in column order; each is listed under its parent).
        self.lower(p);
        let n = p.len();
        let w = &mut self.work;
        w.below_start.clear();
        w.below.clear();
        w.mark.clear();
        w.mark.resize(n, NONE);
        w.tree_parent.clear();
        w.tree_parent.resize(nodes, NONE);
        w.head.clear();
        w.head.resize(nodes, NONE);
        w.next.clear();
        w.next.resize(nodes, NONE);
        w.below_start.push(0);
        for s in 0..nodes {
            let (f, l) = (w.node_start[s] as usize, w.node_start[s + 1] as usize - 1);
            let from = w.below.len();
            for c in f..=l {
                let range = self.lower_start[c] as usize..self.lower_start[c + 1] as usize;
                for &(r, _) in &self.lower[range] {
                    if r as usize > l && w.mark[r as usize] != s as u32 {
                        w.mark[r as usize] = s as u32;
                        w.below.push(r);
                    }
                }
            }
            let mut child = w.head[s];
            while child != NONE {
                let range = w.below_start[child as usize] as usize
                    ..w.below_start[child as usize + 1] as usize;
                for i in range {
                    let r = w.below[i];
                    if r as usize > l && w.mark[r as usize] != s as u32 {
                        w.mark[r as usize] = s as u32;
                        w.below.push(r);
                    }
                }
                child = w.next[child as usize];
            }
            w.below[from..].sort_unstable();
            if let Some(&r) = w.below.get(from) {
                let q = w.node_of[r as usize];
                w.tree_parent[s] = q;
                w.next[s] = w.head[q as usize];
                w.head[q as usize] = s as u32;
            }
            w.below_start.push(w.below.len() as u32);
        }
    }

    /// Relaxed amalgamation: a supernode whose columns just precede its parent's joins
    /// it when the zeros that adds are few. Wider fronts make fewer, denser loops.
    fn amalgamate(&mut self, nodes: usize) {
        let w = &mut self.work;
        // Relaxed amalgamation: a supernode whose columns just precede its parent's
        // joins it when the zeros that adds are few (its columns then take its
        // parent's rows). Wider fronts make fewer, denser loops.
        w.first_of.clear();
        w.first_of.extend_from_slice(&w.node_start[..nodes]);
        w.alive.clear();
        w.alive.resize(nodes, true);
        w.nonzeros.clear();
        for s in 0..nodes {
            let (f, e) = (w.node_start[s] as usize, w.node_start[s + 1] as usize);
            w.nonzeros
                .push((f..e).map(|j| self.count[j] as usize + 1).sum::<usize>());
        }
        for s in 0..nodes {
            let q = w.tree_parent[s];
            if q == NONE || w.node_start[s + 1] != w.first_of[q as usize] {
                continue;
            }
            let q = q as usize;
            let width = |x: usize| (w.node_start[x + 1] - w.first_of[x]) as usize;
            let below = |x: usize| (w.below_start[x + 1] - w.below_start[x]) as usize;
            let (ws, wq) = (width(s), width(q));
            let merged = ws + wq;
            let panel = merged * (merged + below(q));
            let zeros =
                panel - w.nonzeros[s] - w.nonzeros[q] - ws * (ws - 1) / 2 - wq * (wq - 1) / 2
                    + merged * (merged - 1) / 2;
            let allowed = if merged <= 4 {
                1.0
            } else if merged <= 16 {
                0.5
            } else if merged <= 48 {
                0.1
            } else {
                0.05
            };
            if (zeros as f64) > allowed * panel as f64 {
                continue;
            }
            w.first_of[q] = w.first_of[s];
            w.nonzeros[q] = panel - zeros;
            w.alive[s] = false;
        }
        // A child of a supernode that joined its parent is its parent's child: follow
        // the joins (they go up the tree, so the latest parent is found last).
        for s in (0..nodes).rev() {
            let mut q = w.tree_parent[s];
            while q != NONE && !w.alive[q as usize] {
                q = w.tree_parent[q as usize];
            }
            w.tree_parent[s] = q;
        }
        w.head.clear();
        w.head.resize(nodes, NONE);
        w.next.clear();
        w.next.resize(nodes, NONE);
        for s in (0..nodes).filter(|&s| w.alive[s]) {
            let q = w.tree_parent[s];
            if q != NONE {
                w.next[s] = w.head[q as usize];
                w.head[q as usize] = s as u32;
            }
        }
    }

    /// The supernodes in a postorder of their tree, laid out: columns, rows, panels.
    fn lay_out(&mut self, nodes: usize) {
        let w = &mut self.work;
        // Postorder of the supernodal tree.
        w.order.clear();
        w.stack.clear();
        for root in (0..nodes).filter(|&s| w.alive[s] && w.tree_parent[s] == NONE) {
            w.stack.push((root as u32, w.head[root]));
            while let Some(top) = w.stack.last_mut() {
                let (s, child) = *top;
                if child != NONE {
                    top.1 = w.next[child as usize];
                    w.stack.push((child, w.head[child as usize]));
                } else {
                    w.order.push(s);
                    w.stack.pop();
                }
            }
        }
        // Lay the supernodes out in that order.
        self.first.clear();
        self.width.clear();
        self.rows_start.clear();
        self.rows.clear();
        self.children.clear();
        self.panel.clear();
        self.rows_start.push(0);
        let mut panel = 0usize;
        self.largest = 0;
        w.index_of.clear();
        w.index_of.resize(nodes, 0);
        for (k, &s) in w.order.iter().enumerate() {
            let s = s as usize;
            w.index_of[s] = k as u32;
            let (f, width) = (w.first_of[s], w.node_start[s + 1] - w.first_of[s]);
            self.first.push(f);
            self.width.push(width);
            self.rows.extend(f..f + width);
            let below = &w.below[w.below_start[s] as usize..w.below_start[s + 1] as usize];
            self.rows.extend_from_slice(below);
            self.rows_start.push(self.rows.len() as u32);
            let mut children = 0;
            let mut child = w.head[s];
            while child != NONE {
                children += 1;
                child = w.next[child as usize];
            }
            self.children.push(children);
            self.panel.push(panel);
            let m = width as usize + below.len();
            panel += m * width as usize;
            self.largest = self.largest.max(m);
        }
        self.panel.push(panel);
    }

    /// Where each supernode's rows below sit in its parent's front, and the most the
    /// update stack holds.
    fn place_in_parents(&mut self) {
        let w = &mut self.work;
        // Where each supernode's rows below sit in its parent's front, and the most
        // the update stack holds (children's updates wait for their parent).
        self.relative.clear();
        self.relative.resize(self.rows.len(), NONE);
        self.run.clear();
        self.run.resize(self.rows.len(), 0);
        w.held.clear();
        self.stack = 0;
        let mut held = 0;
        for k in 0..w.order.len() {
            for _ in 0..self.children[k] {
                held -= w.held.pop().unwrap_or(0);
            }
            let s = w.order[k] as usize;
            let (start, end) = (self.rows_start[k] as usize, self.rows_start[k + 1] as usize);
            let width = self.width[k] as usize;
            if w.tree_parent[s] != NONE {
                let q = w.index_of[w.tree_parent[s] as usize] as usize;
                let (from, to) = (self.rows_start[q] as usize, self.rows_start[q + 1] as usize);
                for i in start + width..end {
                    let r = self.rows[i];
                    let found = self.rows[from..to].binary_search(&r);
                    self.relative[i] =
                        found.expect("a child's rows are in its parent's front") as u32;
                }
                for i in (start + width..end).rev() {
                    let next = i + 1 < end && self.relative[i + 1] == self.relative[i] + 1;
                    self.run[i] = if next { self.run[i + 1] + 1 } else { 1 };
                }
            }
            let b = end - start - width;
            w.held.push(b * b);
            held += b * b;
            self.stack = self.stack.max(held);
        }
    }

    /// The matrix's lower triangle by column, from the upper pattern of `p`.
    fn lower(&mut self, p: &LdlPattern) {
        let n = p.len();
        self.lower_start.clear();
        self.lower_start.resize(n + 1, 0);
        for k in 0..n {
            for &i in &p.row[p.start[k] as usize..p.start[k + 1] as usize] {
                self.lower_start[i as usize + 1] += 1;
            }
        }
        for c in 0..n {
            self.lower_start[c + 1] += self.lower_start[c];
        }
        self.lower.clear();
        self.lower.resize(p.row.len(), (0, 0));
        let fill = &mut self.work.fill;
        fill.clear();
        fill.extend_from_slice(&self.lower_start[..n]);
        for k in 0..n {
            for slot in p.start[k] as usize..p.start[k + 1] as usize {
                let i = p.row[slot] as usize;
                self.lower[fill[i] as usize] = (k as u32, slot as u32);
                fill[i] += 1;
            }
        }
    }
}

impl SupernodalFactor {
    /// Factor the matrix of `plan` with values `value` (aligned with its pattern's
    /// entries). `scale[k]` is unknown k's natural pivot size: a pivot below
    /// [`DEPENDENT_PIVOT`](super::pivot::DEPENDENT_PIVOT) of it is dropped when `negative[k]` (an edge), and is an
    /// error otherwise; each pivot must have the sign `negative` gives it. With two
    /// `threads` or more, two independent runs of subtrees the plan chose are factored
    /// at once; each front's arithmetic is the same, so the factor is the same bit for
    /// bit.
    pub fn factor(
        &mut self,
        plan: &SupernodalPlan,
        value: &[f64],
        scale: &[f64],
        negative: &[bool],
        threads: usize,
    ) -> Result<(), SingularPivot> {
        let n = plan.n;
        self.panels.resize(*plan.panel.last().unwrap_or(&0), 0.0);
        self.diagonal.clear();
        self.diagonal.resize(n, 0.0);
        self.fronts.reset(plan);
        self.second.dropped = 0;
        let values = Values {
            value,
            scale,
            negative,
        };
        let nodes = plan.first.len();
        let result = match plan.split.filter(|_| threads > 1) {
            None => (self.fronts).run(
                plan,
                0..nodes,
                values,
                &mut self.panels,
                0,
                &mut self.diagonal,
            ),
            Some(split) => self.factor_split(plan, split, values),
        };
        self.dropped = self.fronts.dropped + self.second.dropped;
        result
    }

    /// Solve `L D Lᵀ x = b` in place.
    pub fn solve(&self, plan: &SupernodalPlan, x: &mut [f64]) {
        for k in 0..plan.first.len() {
            let (f, w, rows, panel) = plan.node(k, &self.panels);
            let m = rows.len();
            for c in 0..w {
                let xc = x[f + c];
                if xc != 0.0 {
                    let column = &panel[c * m + c + 1..(c + 1) * m];
                    for (&r, &l) in rows[c + 1..].iter().zip(column) {
                        x[r as usize] -= l * xc;
                    }
                }
            }
        }
        for (x, d) in x.iter_mut().zip(&self.diagonal) {
            *x /= *d;
        }
        for k in (0..plan.first.len()).rev() {
            let (f, w, rows, panel) = plan.node(k, &self.panels);
            let m = rows.len();
            for c in (0..w).rev() {
                let column = &panel[c * m + c + 1..(c + 1) * m];
                let mut s = x[f + c];
                for (&r, &l) in rows[c + 1..].iter().zip(column) {
                    s -= l * x[r as usize];
                }
                x[f + c] = s;
            }
        }
    }
}

impl Fronts {
    /// Ready for a factorization of `plan`: empty stack, a front of the largest size.
    fn reset(&mut self, plan: &SupernodalPlan) {
        self.front.resize(plan.largest * plan.largest, 0.0);
        self.updates.clear();
        self.updates.reserve(plan.stack);
        self.owners.clear();
        self.position.resize(plan.n, 0);
        self.dropped = 0;
    }

    /// Factor the supernodes `nodes` (a run of the postorder whose children outside it
    /// have left their updates on this stack), into `panels` (which start at panel
    /// offset `base`) and `diagonal`.
    fn run(
        &mut self,
        plan: &SupernodalPlan,
        nodes: std::ops::Range<usize>,
        values: Values,
        panels: &mut [f64],
        base: usize,
        diagonal: &mut [f64],
    ) -> Result<(), SingularPivot> {
        let Values {
            value,
            scale,
            negative,
        } = values;
        for k in nodes {
            let (f, w) = (plan.first[k] as usize, plan.width[k] as usize);
            let rows = &plan.rows[plan.rows_start[k] as usize..plan.rows_start[k + 1] as usize];
            let m = rows.len();
            let front = &mut self.front[..m * m];
            front.fill(0.0);
            for (i, &r) in rows.iter().enumerate() {
                self.position[r as usize] = i as u32;
            }
            // The matrix's columns of this supernode.
            for c in 0..w {
                let column = f + c;
                let range =
                    plan.lower_start[column] as usize..plan.lower_start[column + 1] as usize;
                for &(r, slot) in &plan.lower[range] {
                    front[self.position[r as usize] as usize + c * m] += value[slot as usize];
                }
            }
            // The children's updates, last pushed first.
            for _ in 0..plan.children[k] {
                extend_add(plan, &mut self.updates, &mut self.owners, front, m);
            }
            // The pivot columns, and the update matrix below them.
            for c in 0..w {
                let j = f + c;
                let d = front[c + c * m];
                match quasi_definite(d, scale[j], negative[j]) {
                    Pivot::Drop => {
                        // Dependent: its multiplier is zero, and later rows see no coupling.
                        diagonal[j] = f64::NEG_INFINITY;
                        self.dropped += 1;
                        front[c + 1 + c * m..(c + 1) * m].fill(0.0);
                        continue;
                    }
                    Pivot::Fail => return Err(SingularPivot { row: j }),
                    Pivot::Keep => {}
                }
                diagonal[j] = d;
                let (done, rest) = front.split_at_mut((c + 1) * m);
                let column = &mut done[c * m + c + 1..];
                for l in column.iter_mut() {
                    *l /= d;
                }
                // The trailing lower triangle less l d lᵀ: the rest of the pivot block,
                // and the update matrix for the parent below it. (Updating the rows
                // below column by column, every pivot at once, measured 10 % slower.)
                for (t, &lt) in column.iter().enumerate() {
                    if lt == 0.0 {
                        continue;
                    }
                    let scaled = lt * d;
                    let target = &mut rest[t * m + c + 1 + t..(t + 1) * m];
                    for (x, &li) in target.iter_mut().zip(&column[t..]) {
                        *x -= li * scaled;
                    }
                }
            }
            let panel = &mut panels[plan.panel[k] - base..plan.panel[k + 1] - base];
            for c in 0..w {
                panel[c * m..(c + 1) * m].copy_from_slice(&front[c * m..(c + 1) * m]);
            }
            // This supernode's update matrix, for its parent.
            if m > w {
                for c in w..m {
                    self.updates
                        .extend_from_slice(&front[c * m + w..(c + 1) * m]);
                }
                self.owners.push(k as u32);
            }
        }
        Ok(())
    }
}

impl SupernodalPlan {
    /// Supernode k's first column, width, front rows and factor panel.
    fn node<'a>(&'a self, k: usize, panels: &'a [f64]) -> (usize, usize, &'a [u32], &'a [f64]) {
        (
            self.first[k] as usize,
            self.width[k] as usize,
            &self.rows[self.rows_start[k] as usize..self.rows_start[k + 1] as usize],
            &panels[self.panel[k]..self.panel[k + 1]],
        )
    }

    /// Unknowns.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
}

/// Add the update matrix on top of the stack, whose child's index is on top of
/// `owners`, into the front of `m` rows it belongs to, and pop it.
fn extend_add(
    plan: &SupernodalPlan,
    updates: &mut Vec<f64>,
    owners: &mut Vec<u32>,
    front: &mut [f64],
    m: usize,
) {
    let child = owners.pop().expect("a child's update is on the stack") as usize;
    let w = plan.width[child] as usize;
    let (start, end) = (
        plan.rows_start[child] as usize,
        plan.rows_start[child + 1] as usize,
    );
    let b = end - start - w;
    let relative = &plan.relative[start + w..end];
    let run = &plan.run[start + w..end];
    let top = updates.len() - b * b;
    let update = &updates[top..];
    // The child's rows land mostly in runs of consecutive parent rows: each run is added
    // as one slice (every entry still gets its one addition, so the sums are the same).
    for (c, &rc) in relative.iter().enumerate() {
        let column = &update[c * b..(c + 1) * b];
        let base = rc as usize * m;
        let mut r = c;
        while r < b {
            let (first, length) = (relative[r] as usize, run[r] as usize);
            let target = &mut front[base + first..base + first + length];
            for (t, &x) in target.iter_mut().zip(&column[r..r + length]) {
                *t += x;
            }
            r += length;
        }
    }
    updates.truncate(top);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::symbolic::LdlFactor;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// A random quasi-definite system like the contact Newton's: `particles` SPD 2 × 2
    /// blocks coupled at random, and constraints on pairs of particles, each numbered
    /// after both of its particles. Its upper pattern (with repeated entries), values,
    /// and which unknowns are constraints.
    fn system(
        rng: &mut StdRng,
        particles: usize,
        constraints: usize,
    ) -> (LdlPattern, Vec<f64>, Vec<bool>) {
        let mut ends = Vec::new();
        for _ in 0..constraints {
            let a = rng.random_range(0..particles);
            let mut b = rng.random_range(0..particles);
            while b == a {
                b = rng.random_range(0..particles);
            }
            ends.push((a.min(b), a.max(b)));
        }
        let mut unknown = vec![0u32; particles];
        let mut edge_unknown = vec![0u32; constraints];
        let mut negative = Vec::new();
        for (p, unknown) in unknown.iter_mut().enumerate() {
            *unknown = negative.len() as u32;
            negative.extend([false, false]);
            for (k, &(_, b)) in ends.iter().enumerate() {
                if b == p {
                    edge_unknown[k] = negative.len() as u32;
                    negative.push(true);
                }
            }
        }
        let mut entries: Vec<(u32, u32, f64)> = Vec::new();
        let mut add = |i: u32, j: u32, v: f64| entries.push((i.min(j), i.max(j), v));
        for &u in &unknown {
            let m = rng.random_range(1.0..3.0);
            add(u, u, m);
            add(u + 1, u + 1, m);
        }
        for _ in 0..2 * particles {
            let (a, b) = (
                rng.random_range(0..particles),
                rng.random_range(0..particles),
            );
            if a == b {
                continue;
            }
            // A contact-like spring k g gᵀ between the two particles.
            let k = rng.random_range(0.0..5.0);
            let g = [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)];
            for (p, sp) in [(a, 1.0), (b, -1.0)] {
                for (q, sq) in [(a, 1.0), (b, -1.0)] {
                    for x in 0..2 {
                        for y in 0..2 {
                            let (i, j) = (unknown[p] + x, unknown[q] + y);
                            if i <= j {
                                add(i, j, k * sp * sq * g[x as usize] * g[y as usize]);
                            }
                        }
                    }
                }
            }
        }
        for (k, &(a, b)) in ends.iter().enumerate() {
            let d = [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)];
            for (p, sign) in [(a, -1.0), (b, 1.0)] {
                for x in 0..2 {
                    add(unknown[p] + x, edge_unknown[k], sign * d[x as usize]);
                }
            }
        }
        let (pattern, value) = pattern_of(negative.len(), entries);
        (pattern, value, negative)
    }

    /// The upper pattern of `n` unknowns and its values from `(row, column, value)`
    /// entries (`row ≤ column`, repeats allowed), by column.
    fn pattern_of(n: usize, mut entries: Vec<(u32, u32, f64)>) -> (LdlPattern, Vec<f64>) {
        entries.sort_by_key(|e| e.1);
        let (mut start, mut row, mut value) = (vec![0; n + 1], Vec::new(), Vec::new());
        for &(i, j, v) in &entries {
            start[j as usize + 1] += 1;
            row.push(i);
            value.push(v);
        }
        for j in 0..n {
            start[j + 1] += start[j];
        }
        (LdlPattern::new(start, row), value)
    }

    #[test]
    fn random_systems_are_solved_as_the_column_factorization_solves_them() {
        let mut rng = StdRng::seed_from_u64(21);
        for trial in 0..40 {
            let particles = rng.random_range(1..120);
            let constraints = rng.random_range(0..particles);
            let (p, value, negative) = system(&mut rng, particles, constraints);
            let n = p.len();
            let scale = vec![1.0; n];
            let mut reference = LdlFactor::default();
            reference.factor(&p, &value, &scale, &negative).unwrap();
            let plan = SupernodalPlan::new(&p);
            let mut factor = SupernodalFactor::default();
            factor.factor(&plan, &value, &scale, &negative, 1).unwrap();
            assert_eq!(factor.dropped, reference.dropped, "trial {trial}");
            let b: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let (mut x, mut y) = (b.clone(), b);
            reference.solve(&p, &mut x);
            factor.solve(&plan, &mut y);
            let size = x.iter().fold(1.0f64, |a, b| a.max(b.abs()));
            let error = x
                .iter()
                .zip(&y)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(error <= 1e-9 * size, "trial {trial}: {error} of {size}");
        }
    }

    #[test]
    fn a_pivot_of_the_wrong_sign_is_refused() {
        let p = LdlPattern::new(vec![0, 1, 2], vec![0, 1]);
        let plan = SupernodalPlan::new(&p);
        let error =
            SupernodalFactor::default().factor(&plan, &[1.0, -1.0], &[1.0; 2], &[false; 2], 1);
        assert_eq!(error, Err(SingularPivot { row: 1 }));
    }

    /// Two grids of `k × k` particles (two unknowns each) joined by a column of `k`
    /// separator particles numbered last: a tree with two heavy subtrees.
    fn two_grids(rng: &mut StdRng, k: usize) -> (LdlPattern, Vec<f64>) {
        let particles = 2 * k * k + k;
        let index = |block: usize, r: usize, c: usize| block * k * k + r * k + c;
        let separator = |r: usize| 2 * k * k + r;
        let mut pairs = Vec::new();
        for block in 0..2 {
            for r in 0..k {
                for c in 0..k {
                    if c + 1 < k {
                        pairs.push((index(block, r, c), index(block, r, c + 1)));
                    }
                    if r + 1 < k {
                        pairs.push((index(block, r, c), index(block, r + 1, c)));
                    }
                }
            }
        }
        for r in 0..k {
            pairs.push((index(0, r, k - 1), separator(r)));
            pairs.push((index(1, r, 0), separator(r)));
            if r + 1 < k {
                pairs.push((separator(r), separator(r + 1)));
            }
        }
        // Upper entries (i ≤ j) by column j: diagonal dominance keeps it SPD.
        let mut entries: Vec<(u32, u32, f64)> = Vec::new();
        for p in 0..particles {
            for x in 0..2 {
                entries.push(((2 * p + x) as u32, (2 * p + x) as u32, 10.0));
            }
            entries.push((
                (2 * p) as u32,
                (2 * p + 1) as u32,
                rng.random_range(-1.0..1.0),
            ));
        }
        for &(a, b) in &pairs {
            let (a, b) = (a.min(b), a.max(b));
            for x in 0..2 {
                for y in 0..2 {
                    let v = rng.random_range(-1.0..1.0);
                    entries.push(((2 * a + x) as u32, (2 * b + y) as u32, v));
                }
            }
        }
        pattern_of(2 * particles, entries)
    }

    #[test]
    fn two_threads_factor_the_same_bits_as_one() {
        let mut rng = StdRng::seed_from_u64(7);
        let (p, value) = two_grids(&mut rng, 16);
        let n = p.len();
        let (scale, negative) = (vec![1.0; n], vec![false; n]);
        let plan = SupernodalPlan::new(&p);
        assert!(
            split::split_of(&plan).is_some(),
            "the two grids are worth two threads"
        );
        let mut one = SupernodalFactor::default();
        one.factor(&plan, &value, &scale, &negative, 1).unwrap();
        let mut two = SupernodalFactor::default();
        for _ in 0..2 {
            two.factor(&plan, &value, &scale, &negative, 2).unwrap();
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&one.panels), bits(&two.panels));
            assert_eq!(bits(&one.diagonal), bits(&two.diagonal));
        }
        let mut reference = LdlFactor::default();
        reference.factor(&p, &value, &scale, &negative).unwrap();
        let b: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let (mut x, mut y) = (b.clone(), b);
        reference.solve(&p, &mut x);
        two.solve(&plan, &mut y);
        let error = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(error <= 1e-10, "{error}");
    }
}
