//! Cutting a large contact projection in two so that both cores can sweep its rows.
//!
//! The members (islands and loose particles) are cut by position into two sides of
//! about equal row counts; the rows are then those of side 0, those of side 1, and
//! those between the sides. A row of one side moves only that side's particles, so
//! the two sides' rows can be swept at once, the rows between following; every sweep
//! visits them in that order. The cut depends on the problem alone, never on the
//! thread count, so the order of the row updates, and with it the result, is the same
//! bit for bit on one thread or two.

use bevy::math::DVec2;

use super::rows::{ContactRow, RowImpulse};
use crate::constraints::islands::IslandSet;

/// A contact projection with fewer rows than this is swept as one: the cut costs a pass
/// over the rows and a thread hand-off per sweep, which small problems do not repay.
pub const CUT_ROWS: usize = 2048;

/// What a row that pushes weighs against one that is only checked, in the sweeps'
/// work (measured on the furry creature: a row update writes two responses on about
/// 24 particles, a check reads three).
const PUSHING: u32 = 8;

/// Not a particle of a member (or a pinned one, which may end several islands).
const NO_MEMBER: u32 = u32::MAX;

/// Where each row goes once cut.
const SIDE_0: u8 = 0;
const SIDE_1: u8 = 1;
const BETWEEN: u8 = 2;

/// The cut of one contact projection, and its buffers.
#[derive(Clone, Debug, Default)]
pub(super) struct RowCut {
    /// The members (islands by position in the projection's list, then loose particles
    /// after them) in layout order: side 0's first.
    pub(super) members: Vec<u32>,
    /// How many members are on side 0 (all of them when the problem is not cut).
    pub(super) side_0: usize,
    /// The rows (by index in the projection's list) in sweep order: side 0's, side 1's,
    /// then those between.
    pub(super) rows: Vec<u32>,
    /// Where side 0's rows and side 1's rows end in `rows` (both 0 when not cut).
    pub(super) row_ends: (usize, usize),
    member_of: Vec<u32>,
    centre: Vec<DVec2>,
    weight: Vec<u32>,
    side: Vec<u8>,
    order: Vec<u32>,
    class: Vec<u8>,
}

/// The members of a contact projection: the islands `islands` of `set`, then the
/// `loose` particles.
#[derive(Clone, Copy)]
pub(super) struct Members<'a> {
    pub(super) set: &'a IslandSet,
    pub(super) islands: &'a [u32],
    pub(super) loose: &'a [u32],
}

impl Members<'_> {
    fn len(&self) -> usize {
        self.islands.len() + self.loose.len()
    }

    /// Member `m`'s particles: both ends of each of an island's edges, or the loose
    /// particle.
    fn particles(&self, m: usize) -> impl Iterator<Item = usize> + '_ {
        let (edges, loose) = match self.islands.get(m) {
            Some(&i) => (
                &self.set.edges[self.set.islands[i as usize].edges.clone()],
                None,
            ),
            None => (&[][..], Some(self.loose[m - self.islands.len()] as usize)),
        };
        (edges.iter())
            .flat_map(|e| [e.a as usize, e.b as usize])
            .chain(loose)
    }
}

impl RowCut {
    /// Cut `of` and `rows` (`impulses` their warm starts).
    pub(super) fn cut(
        &mut self,
        of: Members,
        position: &[DVec2],
        inverse_mass: &[f64],
        rows: &[ContactRow],
        impulses: &[RowImpulse],
    ) {
        let members = of.len();
        self.members.clear();
        self.members.extend(0..members as u32);
        self.side_0 = members;
        self.rows.clear();
        self.rows.extend(0..rows.len() as u32);
        self.row_ends = (0, 0);
        if rows.len() < CUT_ROWS || members < 2 {
            return;
        }
        self.locate(of, position, inverse_mass);
        self.weigh(rows, impulses, members);
        self.halve(members);
        self.sort_rows(rows);
        for m in 0..members {
            for p in of.particles(m) {
                self.member_of[p] = NO_MEMBER;
            }
        }
        let (end_0, end_1) = self.row_ends;
        if end_0 == 0 || end_1 == end_0 {
            // One side has no rows of its own: nothing to sweep at once.
            self.members.sort_unstable();
            self.side_0 = members;
            self.rows.sort_unstable();
            self.row_ends = (0, 0);
        }
    }

    /// Each member's free particles and centre (the mean of its particles, an
    /// island's counted once per edge end).
    fn locate(&mut self, of: Members, position: &[DVec2], inverse_mass: &[f64]) {
        if self.member_of.len() < inverse_mass.len() {
            self.member_of.resize(inverse_mass.len(), NO_MEMBER);
        }
        self.centre.clear();
        for m in 0..of.len() {
            let (mut sum, mut count) = (DVec2::ZERO, 0usize);
            for p in of.particles(m) {
                sum += position[p];
                count += 1;
                if inverse_mass[p] > 0.0 {
                    self.member_of[p] = m as u32;
                }
            }
            self.centre.push(sum / count.max(1) as f64);
        }
    }

    /// Each member's share of the sweeps' work: the rows that touch it, a row that
    /// starts with an impulse (it will most likely update every sweep, writing its
    /// response on every particle of its members) counting as [`PUSHING`] rows.
    fn weigh(&mut self, rows: &[ContactRow], impulses: &[RowImpulse], members: usize) {
        self.weight.clear();
        self.weight.resize(members, 0);
        for (c, row) in rows.iter().enumerate() {
            let pushing = impulses.get(c).is_some_and(|i| i.normal > 0.0);
            let weight = if pushing { PUSHING } else { 1 };
            let touched = self.members_of(row);
            for (i, &m) in touched.iter().enumerate() {
                if m != NO_MEMBER && !touched[..i].contains(&m) {
                    self.weight[m as usize] += weight;
                }
            }
        }
    }

    /// Side 0: the members first along the wider axis of their centres, up to half the
    /// rows' weight.
    fn halve(&mut self, members: usize) {
        let (low, high) = self.centre.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(low, high), c| (low.min(*c), high.max(*c)),
        );
        let extent = high - low;
        let axis = if extent.x >= extent.y { 0 } else { 1 };
        self.order.clear();
        self.order.extend(0..members as u32);
        let centre = &self.centre;
        self.order.sort_unstable_by(|&a, &b| {
            (centre[a as usize][axis])
                .total_cmp(&centre[b as usize][axis])
                .then(a.cmp(&b))
        });
        let total: u64 = self.weight.iter().map(|&w| u64::from(w)).sum();
        self.side.clear();
        self.side.resize(members, SIDE_1);
        let mut seen = 0u64;
        for &m in &self.order {
            if 2 * seen >= total {
                break;
            }
            seen += u64::from(self.weight[m as usize]);
            self.side[m as usize] = SIDE_0;
        }
        self.members.clear();
        for want in [SIDE_0, SIDE_1] {
            (self.members).extend((0..members as u32).filter(|&m| self.side[m as usize] == want));
        }
        self.side_0 = self.side.iter().filter(|&&s| s == SIDE_0).count();
    }

    /// The rows in sweep order: side 0's, side 1's, then those between (or touching no
    /// member), each in the order given.
    fn sort_rows(&mut self, rows: &[ContactRow]) {
        self.class.clear();
        for row in rows {
            let mut class = None;
            for m in self.members_of(row) {
                if m == NO_MEMBER {
                    continue;
                }
                let side = self.side[m as usize];
                class = match class {
                    None => Some(side),
                    Some(c) if c == side => Some(c),
                    Some(_) => Some(BETWEEN),
                };
            }
            self.class.push(class.unwrap_or(BETWEEN));
        }
        let classes = &self.class;
        let of = |want: u8| (0..rows.len() as u32).filter(move |&c| classes[c as usize] == want);
        self.rows.clear();
        self.rows.extend(of(SIDE_0));
        let end_0 = self.rows.len();
        self.rows.extend(of(SIDE_1));
        self.row_ends = (end_0, self.rows.len());
        self.rows.extend(of(BETWEEN));
    }

    /// The member of each of `row`'s free particles.
    fn members_of(&self, row: &ContactRow) -> [u32; 3] {
        let mut out = [NO_MEMBER; 3];
        for ((slot, &p), &k) in out.iter_mut().zip(&row.particles).zip(&row.coefficients) {
            if k != 0.0 {
                *slot = self.member_of.get(p as usize).copied().unwrap_or(NO_MEMBER);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::islands::find_islands;
    use crate::model::Edge;

    /// Four strands of three particles: two near x = 0, two near x = 1 (higher up, so
    /// the wider axis is still x).
    fn four_strands() -> (IslandSet, Vec<DVec2>, Vec<f64>) {
        let mut position = Vec::new();
        let mut edges = Vec::new();
        for (s, x) in [0.0, 0.01, 1.0, 1.01].into_iter().enumerate() {
            let first = position.len() as u32;
            position.extend((0..3).map(|i| DVec2::new(x, 0.2 * s as f64 + 0.01 * i as f64)));
            edges.push(Edge::new(first, first + 1, 0.01));
            edges.push(Edge::new(first + 1, first + 2, 0.01));
        }
        let inverse_mass = vec![1.0; position.len()];
        let set = find_islands(&edges, &vec![false; position.len()]);
        (set, position, inverse_mass)
    }

    /// A row from particle `p` to the edge `(q, r)`.
    fn row(p: u32, q: u32, r: u32) -> ContactRow {
        ContactRow {
            particles: [p, q, r],
            coefficients: [1.0, -0.5, -0.5],
            normal: DVec2::Y,
            target: 0.0,
            friction: 0.0,
        }
    }

    /// The islands `islands` of `set`, no loose particles.
    fn members<'a>(set: &'a IslandSet, islands: &'a [u32]) -> Members<'a> {
        Members {
            set,
            islands,
            loose: &[],
        }
    }

    /// Every island of `set`, in order.
    fn islands_of(set: &IslandSet) -> Vec<u32> {
        (0..set.islands.len() as u32).collect()
    }

    #[test]
    fn a_large_problem_is_cut_into_two_sides_and_the_rows_between() {
        let (set, position, inverse_mass) = four_strands();
        let islands = islands_of(&set);
        // Which island holds particle 0 (strand 0), 3 (strand 1), ...
        let island_of = |p: u32| {
            (set.islands.iter())
                .position(|i| {
                    set.edges[i.edges.clone()]
                        .iter()
                        .any(|e| e.a == p || e.b == p)
                })
                .expect("in an island") as u32
        };
        // Rows alternate: within the left pair, within the right pair, and every tenth
        // between strand 1 (left) and strand 2 (right).
        let mut rows = Vec::new();
        for k in 0..2400 {
            rows.push(match k % 10 {
                9 => row(4, 6, 7),
                k if k % 2 == 0 => row(0, 3, 4),
                _ => row(9, 6, 7),
            });
        }
        let mut cut = RowCut::default();
        cut.cut(
            members(&set, &islands),
            &position,
            &inverse_mass,
            &rows,
            &[],
        );
        let left = [island_of(0), island_of(3)];
        let right = [island_of(6), island_of(9)];
        assert_eq!(cut.side_0, 2);
        let mut side_0 = cut.members[..2].to_vec();
        side_0.sort_unstable();
        let mut expect = left.to_vec();
        expect.sort_unstable();
        // Side 0 is the left pair, first along x, the wider axis.
        assert_eq!(side_0, expect, "right: {right:?}");
        let (end_0, end_1) = cut.row_ends;
        assert_eq!((end_0, end_1 - end_0, rows.len() - end_1), (1200, 960, 240));
        let class = |c: u32| c % 10;
        assert!(
            cut.rows[..end_0]
                .iter()
                .all(|&c| class(c) % 2 == 0 && class(c) != 9)
        );
        assert!(
            cut.rows[end_0..end_1]
                .iter()
                .all(|&c| class(c) % 2 == 1 && class(c) != 9)
        );
        assert!(cut.rows[end_1..].iter().all(|&c| class(c) == 9));
        // Each group keeps the rows' own order, and every row is there once.
        for group in [
            &cut.rows[..end_0],
            &cut.rows[end_0..end_1],
            &cut.rows[end_1..],
        ] {
            assert!(group.windows(2).all(|w| w[0] < w[1]));
        }
        let mut all = cut.rows.clone();
        all.sort_unstable();
        assert_eq!(all, (0..rows.len() as u32).collect::<Vec<_>>());
        // The marks are cleared for the next cut.
        assert!(cut.member_of.iter().all(|&m| m == NO_MEMBER));
    }

    #[test]
    fn small_problems_and_problems_with_one_side_only_are_not_cut() {
        let (set, position, inverse_mass) = four_strands();
        let islands = islands_of(&set);
        let mut cut = RowCut::default();
        let few = vec![row(0, 3, 4); CUT_ROWS - 1];
        cut.cut(members(&set, &islands), &position, &inverse_mass, &few, &[]);
        assert_eq!(cut.row_ends, (0, 0));
        assert_eq!(cut.side_0, islands.len());
        assert_eq!(cut.members, islands);
        // Enough rows, but all between the left pair and the right: no side has rows
        // of its own.
        let between = vec![row(4, 6, 7); CUT_ROWS];
        cut.cut(
            members(&set, &islands),
            &position,
            &inverse_mass,
            &between,
            &[],
        );
        assert_eq!(cut.row_ends, (0, 0));
        assert_eq!(cut.members, islands);
        assert_eq!(cut.rows, (0..CUT_ROWS as u32).collect::<Vec<_>>());
    }
}
