//! Two threads in one factorization: two runs of sibling subtrees of the supernodal
//! tree share no front, so they are factored at once, each with its own fronts and
//! stack. Their stacks, laid one on the other in factor order, are the stack the
//! sequential factorization would have left, so every later front adds the same
//! updates in the same order: the factor is the same bit for bit.

use super::{NONE, SupernodalFactor, SupernodalPlan, Values};
use crate::linalg::pivot::SingularPivot;

/// Less than this much work (multiply–adds, about 0.2 ns each) on the smaller side is
/// not worth a thread (spawning one costs some tens of microseconds).
const WORTH_A_THREAD: f64 = 5e5;

/// Supernodes `first..middle` and `middle..end` (in factor order) are runs of sibling
/// subtrees: factored on two threads after `..first`, before `end..`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Split {
    first: usize,
    middle: usize,
    end: usize,
}

/// The split that leaves the most work to the second thread: down the tree's heavy
/// path, at each node its children cut in two runs as evenly as they go.
pub(super) fn choose(plan: &mut SupernodalPlan) -> Option<Split> {
    let nodes = plan.first.len();
    let w = &mut plan.work;
    // Each supernode's own work, its subtree's, and its subtree's first supernode.
    w.subtree.clear();
    w.subtree_start.clear();
    for k in 0..nodes {
        let m = (plan.rows_start[k + 1] - plan.rows_start[k]) as f64;
        let width = plan.width[k] as f64;
        w.subtree.push(width * m * m);
        w.subtree_start.push(k as u32);
    }
    for k in 0..nodes {
        let s = w.order[k] as usize;
        let q = w.tree_parent[s];
        if q != NONE {
            let q = w.index_of[q as usize] as usize;
            w.subtree[q] += w.subtree[k];
            w.subtree_start[q] = w.subtree_start[q].min(w.subtree_start[k]);
        }
    }
    let (subtree, start) = (&w.subtree, &w.subtree_start);
    // Children of node p (the virtual root is `nodes`), last first: the last child is
    // just before its parent, each earlier one just before its next sibling's subtree.
    let first_of = |p: usize| if p == nodes { 0 } else { start[p] as usize };
    let mut best: Option<(f64, Split)> = None;
    let mut p = nodes;
    loop {
        let (lowest, mut c) = (first_of(p), p);
        let mut total = 0.0;
        let mut heaviest: Option<usize> = None;
        while c > lowest {
            let child = c - 1;
            total += subtree[child];
            if heaviest.is_none_or(|h| subtree[child] > subtree[h]) {
                heaviest = Some(child);
            }
            c = start[child] as usize;
        }
        // Cut after each child in turn (from the last): the later run's work grows.
        let (mut c, mut later) = (p, 0.0);
        while c > lowest {
            let child = c - 1;
            later += subtree[child];
            let middle = start[child] as usize;
            let gain = later.min(total - later);
            if middle > lowest && best.is_none_or(|(g, _)| gain > g) {
                let split = Split {
                    first: lowest,
                    middle,
                    end: p,
                };
                best = Some((gain, split));
            }
            c = middle;
        }
        match heaviest {
            Some(h) if best.is_none_or(|(g, _)| subtree[h] > 2.0 * g) => p = h,
            _ => break,
        }
    }
    best.filter(|(gain, _)| *gain >= WORTH_A_THREAD)
        .map(|(_, split)| split)
}

impl SupernodalFactor {
    /// The factorization cut by `split`: its first run on this thread, its second on
    /// another, the rest before and after them on this thread.
    pub(super) fn factor_split(
        &mut self,
        plan: &SupernodalPlan,
        split: Split,
        values: Values,
    ) -> Result<(), SingularPivot> {
        let Split { first, middle, end } = split;
        let nodes = plan.first.len();
        let fronts = &mut self.fronts;
        fronts.run(
            plan,
            0..first,
            values,
            &mut self.panels,
            0,
            &mut self.diagonal,
        )?;
        let second = &mut self.second;
        second.reset(plan);
        self.second_diagonal.clear();
        self.second_diagonal.resize(plan.n, 0.0);
        let cut = plan.panel[middle];
        let (left, right) = self.panels.split_at_mut(cut);
        let (diagonal, second_diagonal) = (&mut self.diagonal, &mut self.second_diagonal);
        let (ours, theirs) = std::thread::scope(|scope| {
            let theirs = scope
                .spawn(move || second.run(plan, middle..end, values, right, cut, second_diagonal));
            let ours = fronts.run(plan, first..middle, values, left, 0, diagonal);
            let theirs = theirs
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p));
            (ours, theirs)
        });
        // An error the sequential factorization would have met first comes first.
        ours?;
        theirs?;
        for k in middle..end {
            let columns = plan.first[k] as usize..(plan.first[k] + plan.width[k]) as usize;
            self.diagonal[columns.clone()].copy_from_slice(&self.second_diagonal[columns]);
        }
        let (fronts, second) = (&mut self.fronts, &self.second);
        fronts.updates.extend_from_slice(&second.updates);
        fronts.owners.extend_from_slice(&second.owners);
        fronts.run(
            plan,
            end..nodes,
            values,
            &mut self.panels,
            0,
            &mut self.diagonal,
        )
    }
}

#[cfg(test)]
pub(super) fn split_of(plan: &SupernodalPlan) -> Option<Split> {
    plan.split
}
