//! Broad phase: which point–edge (and edge–edge) pairs can touch this step.
//!
//! Every edge's swept box (its endpoints at the start and end of the step, inflated by
//! the margin) is entered into a uniform grid, hashed into a table and stored by
//! counting sort in reused buffers; each point's swept segment then queries the cells
//! it covers. Cost grows near-linearly with the number of edges in a pile. Brute force
//! (every pair) stays available for testing.

use bevy::math::DVec2;
use bevy::prelude::Reflect;

use crate::model::Edge;

/// How candidate pairs are found.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum BroadPhaseMethod {
    /// Uniform hashed grid: near-linear.
    #[default]
    Grid,
    /// Every pair: quadratic, for testing.
    BruteForce,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec2,
    /// Upper corner.
    pub max: DVec2,
}

impl Aabb {
    /// The box of a segment's sweep: both endpoints at the start and at the end.
    pub fn swept(points: &[DVec2], margin: f64) -> Aabb {
        let (mut min, mut max) = (points[0], points[0]);
        for &p in &points[1..] {
            min = min.min(p);
            max = max.max(p);
        }
        Aabb {
            min: min - DVec2::splat(margin),
            max: max + DVec2::splat(margin),
        }
    }

    /// Whether the boxes overlap (touching counts).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.x <= other.max.x
            && other.min.x <= self.max.x
            && self.min.y <= other.max.y
            && other.min.y <= self.max.y
    }
}

/// More cells than this and an edge is checked against every query instead.
const MAX_CELLS_PER_EDGE: i64 = 4096;

/// Reusable broad-phase buffers.
#[derive(Clone, Debug, Default)]
pub struct BroadPhase {
    edge_boxes: Vec<Aabb>,
    /// Each edge's cell range, `None` when oversized: computed once per build.
    edge_cells: Vec<Option<CellRange>>,
    /// One over the cell's side: cells are found by a product, not a division (four
    /// per box, the build's longest latency).
    inverse_cell: f64,
    mask: usize,
    /// The cells every entered box lies in, when few enough to index directly (row by
    /// row: the edges of a strand, entered one after another, fill neighbouring
    /// buckets); `None`: the cells are hashed.
    dense: Option<CellRange>,
    bucket_start: Vec<u32>,
    entries: Vec<u32>,
    oversized: Vec<u32>,
    cursor: Vec<u32>,
    seen: Vec<u32>,
    lanes: Vec<QueryLane>,
}

/// Below this many queries (points, or edges for the crossing count) the queries stay
/// on one thread: a query costs about half a microsecond, starting a thread tens.
const PARALLEL_QUERIES: usize = 4096;

/// One extra thread's share of the broad phase's queries: its range, its stamps, its
/// pairs.
#[derive(Clone, Debug, Default)]
struct QueryLane {
    range: std::ops::Range<usize>,
    seen: Vec<u32>,
    pairs: Vec<(u32, u32)>,
}

/// Cells `x0..=x1` by `y0..=y1`.
type CellRange = (i64, i64, i64, i64);

/// `v.floor() as i64`, without the library call `floor` is on baseline x86-64 (it was
/// a tenth of a step in free fall): the same value for every `v`, ±∞ and NaN included.
fn floor_to_i64(v: f64) -> i64 {
    let truncated = v as i64;
    if (truncated as f64) > v {
        truncated.saturating_sub(1)
    } else {
        truncated
    }
}

fn hash(ix: i64, iy: i64, mask: usize) -> usize {
    ((ix.wrapping_mul(73_856_093) ^ iy.wrapping_mul(19_349_663)) as u64 as usize) & mask
}

/// A grid of at most this many cells per edge is indexed directly, not hashed.
const DENSE_CELLS_PER_EDGE: i64 = 8;

impl BroadPhase {
    fn cell_range(&self, b: &Aabb) -> CellRange {
        let f = |v: f64| floor_to_i64(v * self.inverse_cell);
        (f(b.min.x), f(b.min.y), f(b.max.x), f(b.max.y))
    }

    /// The bucket of a cell (inside the dense grid, when there is one).
    fn bucket(&self, ix: i64, iy: i64) -> usize {
        match self.dense {
            Some((x0, y0, x1, _)) => ((iy - y0) * (x1 - x0 + 1) + (ix - x0)) as usize,
            None => hash(ix, iy, self.mask),
        }
    }

    /// The cells of a box, or `None` when it is better tested against everything than
    /// entered in the grid.
    fn cells(&self, b: &Aabb) -> Option<CellRange> {
        let range @ (x0, y0, x1, y1) = self.cell_range(b);
        let oversized = !b.min.is_finite()
            || !b.max.is_finite()
            || x1
                .saturating_sub(x0)
                .saturating_add(1)
                .saturating_mul(y1.saturating_sub(y0).saturating_add(1))
                > MAX_CELLS_PER_EDGE;
        (!oversized).then_some(range)
    }

    /// Build the grid over every edge's swept box: positions `x`, end positions
    /// `x + d` (`None`: not moving), inflated by `margin`.
    pub fn build(
        &mut self,
        edges: &[Edge],
        position: &[DVec2],
        displacement: Option<&[DVec2]>,
        margin: f64,
    ) {
        self.build_boxes(edges.iter(), position, displacement, margin);
    }

    fn build_boxes<'e>(
        &mut self,
        edges: impl ExactSizeIterator<Item = &'e Edge>,
        position: &[DVec2],
        displacement: Option<&[DVec2]>,
        margin: f64,
    ) {
        self.edge_boxes.clear();
        let mut extent = 0.0;
        let count = edges.len().max(1);
        for e in edges {
            let (a, b) = (e.a as usize, e.b as usize);
            let (da, db) = displacement.map_or((DVec2::ZERO, DVec2::ZERO), |d| (d[a], d[b]));
            let b = Aabb::swept(
                &[position[a], position[b], position[a] + da, position[b] + db],
                margin,
            );
            let size = b.max - b.min;
            if size.is_finite() {
                extent += size.max_element();
            }
            self.edge_boxes.push(b);
        }
        // A cell about the size of a typical edge's box.
        self.inverse_cell = 1.0 / (extent / count as f64).max(1e-9);
        self.oversized.clear();
        self.edge_cells.clear();
        let mut bounds: Option<CellRange> = None;
        for k in 0..self.edge_boxes.len() {
            let cells = self.cells(&self.edge_boxes[k]);
            self.edge_cells.push(cells);
            match (cells, &mut bounds) {
                (None, _) => self.oversized.push(k as u32),
                (Some(c), None) => bounds = Some(c),
                (Some(c), Some(b)) => {
                    *b = (b.0.min(c.0), b.1.min(c.1), b.2.max(c.2), b.3.max(c.3));
                }
            }
        }
        self.dense = bounds.filter(|&(x0, y0, x1, y1)| {
            let cells = (x1 - x0 + 1).saturating_mul(y1 - y0 + 1);
            cells <= DENSE_CELLS_PER_EDGE.saturating_mul(count as i64)
        });
        let table = match self.dense {
            Some((x0, y0, x1, y1)) => ((x1 - x0 + 1) * (y1 - y0 + 1)) as usize,
            None => (2 * count).next_power_of_two(),
        };
        self.mask = table.next_power_of_two() - 1;
        self.bucket_start.clear();
        self.bucket_start.resize(table + 1, 0);

        // Count, prefix-sum, fill: a counting sort of (bucket, edge) entries.
        for k in 0..self.edge_boxes.len() {
            let Some((x0, y0, x1, y1)) = self.edge_cells[k] else {
                continue;
            };
            for iy in y0..=y1 {
                for ix in x0..=x1 {
                    let bucket = self.bucket(ix, iy);
                    self.bucket_start[bucket + 1] += 1;
                }
            }
        }
        for i in 1..=table {
            self.bucket_start[i] += self.bucket_start[i - 1];
        }
        self.entries.clear();
        self.entries.resize(self.bucket_start[table] as usize, 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.bucket_start[..table]);
        for k in 0..self.edge_boxes.len() {
            let Some((x0, y0, x1, y1)) = self.edge_cells[k] else {
                continue;
            };
            for iy in y0..=y1 {
                for ix in x0..=x1 {
                    let bucket = self.bucket(ix, iy);
                    self.entries[self.cursor[bucket] as usize] = k as u32;
                    self.cursor[bucket] += 1;
                }
            }
        }
    }

    /// Visit each edge whose box overlaps `query` (its cells `cells`) once, in a fixed
    /// order. `stamp` must differ between consecutive queries on `seen` and be
    /// non-zero.
    fn visit_cells(
        &self,
        query: &Aabb,
        cells: Option<CellRange>,
        seen: &mut [u32],
        stamp: u32,
        mut visit: impl FnMut(u32),
    ) {
        let Some((x0, y0, x1, y1)) = cells else {
            // A huge query: test every edge.
            for k in 0..self.edge_boxes.len() as u32 {
                if self.edge_boxes[k as usize].overlaps(query) {
                    visit(k);
                }
            }
            return;
        };
        // Cells outside a dense grid hold nothing.
        let (x0, y0, x1, y1) = match self.dense {
            Some(g) => (x0.max(g.0), y0.max(g.1), x1.min(g.2), y1.min(g.3)),
            None => (x0, y0, x1, y1),
        };
        for iy in y0..=y1 {
            for ix in x0..=x1 {
                let bucket = self.bucket(ix, iy);
                for slot in self.bucket_start[bucket]..self.bucket_start[bucket + 1] {
                    let k = self.entries[slot as usize];
                    if seen[k as usize] != stamp {
                        seen[k as usize] = stamp;
                        if self.edge_boxes[k as usize].overlaps(query) {
                            visit(k);
                        }
                    }
                }
            }
        }
        for i in 0..self.oversized.len() {
            let k = self.oversized[i];
            if self.edge_boxes[k as usize].overlaps(query) {
                visit(k);
            }
        }
    }

    fn reset_seen(&mut self) {
        self.seen.clear();
        self.seen.resize(self.edge_boxes.len(), 0);
    }

    /// Append every (point, edge) pair whose swept boxes overlap and for which `keep`
    /// holds, in point order (within a point, in an order fixed by the grid).
    /// Call [`BroadPhase::build`] first. With `threads` above one and enough points,
    /// contiguous ranges of points are queried on that many threads and their pairs
    /// appended in order: the same pairs in the same order whatever the count.
    pub fn point_edge_pairs(
        &mut self,
        method: BroadPhaseMethod,
        threads: usize,
        position: &[DVec2],
        displacement: &[DVec2],
        keep: impl Fn(u32, u32) -> bool + Sync,
        pairs: &mut Vec<(u32, u32)>,
    ) {
        self.reset_seen();
        let n = position.len();
        if method == BroadPhaseMethod::BruteForce {
            for i in 0..n {
                let query = Aabb::swept(&[position[i], position[i] + displacement[i]], 0.0);
                for k in 0..self.edge_boxes.len() as u32 {
                    if self.edge_boxes[k as usize].overlaps(&query) && keep(i as u32, k) {
                        pairs.push((i as u32, k));
                    }
                }
            }
            return;
        }
        self.in_shares(
            n,
            threads,
            pairs,
            |this, points, seen, pairs| {
                this.query_points(points, position, displacement, &keep, seen, pairs)
            },
            |(), ()| (),
        );
    }

    /// Run `work` over `0..n` in contiguous shares, each stamping its own `seen` and
    /// appending to its own pairs: on one share into `pairs` below [`PARALLEL_QUERIES`]
    /// or with one thread; else the first share on this thread into `pairs`, the others
    /// on scoped threads into their lanes, appended to `pairs` in order after. The
    /// shares' results are folded in order with `combine`: nothing depends on `threads`.
    fn in_shares<R: Send>(
        &mut self,
        n: usize,
        threads: usize,
        pairs: &mut Vec<(u32, u32)>,
        work: impl Fn(&Self, std::ops::Range<usize>, &mut [u32], &mut Vec<(u32, u32)>) -> R + Sync,
        combine: impl Fn(R, R) -> R,
    ) -> R {
        let threads = threads.min(n);
        let mut seen = std::mem::take(&mut self.seen);
        if threads <= 1 || n < PARALLEL_QUERIES {
            let result = work(self, 0..n, &mut seen, pairs);
            self.seen = seen;
            return result;
        }
        let mut lanes = std::mem::take(&mut self.lanes);
        lanes.resize_with(threads - 1, QueryLane::default);
        for (t, lane) in lanes.iter_mut().enumerate() {
            lane.range = n * (t + 1) / threads..n * (t + 2) / threads;
            lane.seen.clear();
            lane.seen.resize(self.edge_boxes.len(), 0);
            lane.pairs.clear();
        }
        let (this, work) = (&*self, &work);
        let (first, rest) = std::thread::scope(|scope| {
            let handles: Vec<_> = (lanes.iter_mut())
                .map(|lane| {
                    scope.spawn(move || {
                        let QueryLane { range, seen, pairs } = lane;
                        work(this, range.clone(), seen, pairs)
                    })
                })
                .collect();
            let first = work(this, 0..n / threads, &mut seen, pairs);
            let rest: Vec<R> = (handles.into_iter())
                .map(|h| h.join().expect("a broad-phase thread panicked"))
                .collect();
            (first, rest)
        });
        for lane in &lanes {
            pairs.extend_from_slice(&lane.pairs);
        }
        self.seen = seen;
        self.lanes = lanes;
        rest.into_iter().fold(first, combine)
    }

    /// The grid queries of the points in `points`, stamped in `seen`.
    fn query_points(
        &self,
        points: std::ops::Range<usize>,
        position: &[DVec2],
        displacement: &[DVec2],
        keep: &(impl Fn(u32, u32) -> bool + Sync),
        seen: &mut [u32],
        pairs: &mut Vec<(u32, u32)>,
    ) {
        for i in points {
            let query = Aabb::swept(&[position[i], position[i] + displacement[i]], 0.0);
            let point = i as u32;
            let cells = self.cells(&query);
            self.visit_cells(&query, cells, seen, point + 1, |k| {
                if keep(point, k) {
                    pairs.push((point, k));
                }
            });
        }
    }

    /// Over every pair of edges (j < k) whose boxes overlap, in the order
    /// [`BroadPhase::edge_edge_pairs`] gives them, how many `test` holds for, and the
    /// first. With `threads` above one and enough edges, contiguous ranges of j are
    /// tested on that many threads: the same count and the same first pair whatever the
    /// count. Call [`BroadPhase::build`] first.
    pub fn count_edge_pairs(
        &mut self,
        threads: usize,
        test: impl Fn(u32, u32) -> bool + Sync,
    ) -> (usize, Option<(u32, u32)>) {
        self.reset_seen();
        let n = self.edge_boxes.len();
        // Counted as found: the shares' pair lists stay empty.
        let mut none = Vec::new();
        self.in_shares(
            n,
            threads,
            &mut none,
            |this, range, seen, _| this.count_edges(range, &test, seen),
            |(count, found), (c, f)| (count + c, found.or(f)),
        )
    }

    /// [`BroadPhase::count_edge_pairs`] over the edges `range` as the first of a pair.
    fn count_edges(
        &self,
        range: std::ops::Range<usize>,
        test: &(impl Fn(u32, u32) -> bool + Sync),
        seen: &mut [u32],
    ) -> (usize, Option<(u32, u32)>) {
        let (mut count, mut first) = (0, None);
        for j in range {
            let j = j as u32;
            let query = self.edge_boxes[j as usize];
            let cells = self.edge_cells[j as usize];
            self.visit_cells(&query, cells, seen, j + 1, |k| {
                if k > j && test(j, k) {
                    count += 1;
                    first.get_or_insert((j, k));
                }
            });
        }
        (count, first)
    }

    /// Append every pair of edges (j < k) whose boxes overlap and for which `keep`
    /// holds. Call [`BroadPhase::build`] first.
    pub fn edge_edge_pairs(
        &mut self,
        method: BroadPhaseMethod,
        keep: impl Fn(u32, u32) -> bool,
        pairs: &mut Vec<(u32, u32)>,
    ) {
        self.reset_seen();
        let mut seen = std::mem::take(&mut self.seen);
        for j in 0..self.edge_boxes.len() as u32 {
            let query = self.edge_boxes[j as usize];
            match method {
                BroadPhaseMethod::Grid => {
                    let cells = self.edge_cells[j as usize];
                    self.visit_cells(&query, cells, &mut seen, j + 1, |k| {
                        if k > j && keep(j, k) {
                            pairs.push((j, k));
                        }
                    })
                }
                BroadPhaseMethod::BruteForce => {
                    for k in j + 1..self.edge_boxes.len() as u32 {
                        if self.edge_boxes[k as usize].overlaps(&query) && keep(j, k) {
                            pairs.push((j, k));
                        }
                    }
                }
            }
        }
        self.seen = seen;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    fn random_scene(rng: &mut StdRng, strands: usize) -> (Vec<DVec2>, Vec<DVec2>, Vec<Edge>) {
        let (mut position, mut displacement, mut edges) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..strands {
            let mut x = DVec2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
            let first = position.len() as u32;
            for i in 0..20 {
                position.push(x);
                displacement.push(DVec2::new(
                    rng.random_range(-0.01..0.01),
                    rng.random_range(-0.01..0.01),
                ));
                x += 0.01 * DVec2::from_angle(rng.random_range(0.0..6.3));
                if i > 0 {
                    edges.push(Edge::new(first + i - 1, first + i, 0.01));
                }
            }
        }
        // A long static wall across everything.
        position.push(DVec2::new(-0.5, 0.5));
        position.push(DVec2::new(1.5, 0.5));
        displacement.extend([DVec2::ZERO; 2]);
        let n = position.len() as u32;
        edges.push(Edge {
            a: n - 2,
            b: n - 1,
            is_static: true,
            ..edges[0]
        });
        (position, displacement, edges)
    }

    #[test]
    fn grid_and_brute_force_find_the_same_pairs() {
        let mut rng = StdRng::seed_from_u64(9);
        let mut dense_seen = false;
        for (strands, far) in [
            (1, false),
            (10, false),
            (100, false),
            (10, true),
            (100, true),
        ] {
            let (mut position, mut displacement, mut edges) = random_scene(&mut rng, strands);
            if far {
                // One edge far away: too many cells between to index, so they are hashed.
                let n = position.len() as u32;
                position.extend([DVec2::splat(1e3), DVec2::splat(1e3 + 0.01)]);
                displacement.extend([DVec2::ZERO; 2]);
                edges.push(Edge::new(n, n + 1, 0.01));
            }
            let keep = |p: u32, k: u32| edges[k as usize].a != p && edges[k as usize].b != p;
            let mut broad = BroadPhase::default();
            broad.build(&edges, &position, Some(&displacement), 0.004);
            if far {
                assert!(broad.dense.is_none(), "{strands} strands: hashed");
            }
            dense_seen |= broad.dense.is_some();
            let (mut grid, mut brute) = (Vec::new(), Vec::new());
            broad.point_edge_pairs(
                BroadPhaseMethod::Grid,
                1,
                &position,
                &displacement,
                keep,
                &mut grid,
            );
            broad.point_edge_pairs(
                BroadPhaseMethod::BruteForce,
                1,
                &position,
                &displacement,
                keep,
                &mut brute,
            );
            grid.sort_unstable();
            brute.sort_unstable();
            assert_eq!(grid, brute, "{strands} strands, far {far}");
            assert!(!grid.is_empty());
            let (mut grid, mut brute) = (Vec::new(), Vec::new());
            broad.edge_edge_pairs(BroadPhaseMethod::Grid, |_, _| true, &mut grid);
            broad.edge_edge_pairs(BroadPhaseMethod::BruteForce, |_, _| true, &mut brute);
            grid.sort_unstable();
            brute.sort_unstable();
            assert_eq!(grid, brute, "{strands} strands, far {far}");
        }
        assert!(dense_seen, "a crowded scene is indexed directly");
    }

    #[test]
    fn counting_edge_pairs_on_two_threads_matches_one_and_the_pair_list() {
        let mut rng = StdRng::seed_from_u64(4);
        let (position, displacement, edges) = random_scene(&mut rng, 1000);
        assert!(edges.len() >= PARALLEL_QUERIES, "{} edges", edges.len());
        let mut broad = BroadPhase::default();
        broad.build(&edges, &position, Some(&displacement), 0.004);
        let test = |j: u32, k: u32| (j + k).is_multiple_of(3);
        let mut listed = Vec::new();
        broad.edge_edge_pairs(BroadPhaseMethod::Grid, test, &mut listed);
        let one = broad.count_edge_pairs(1, test);
        assert!(one.0 > 1000, "{one:?}");
        assert_eq!(one, (listed.len(), listed.first().copied()));
        assert_eq!(broad.count_edge_pairs(2, test), one);
        assert_eq!(broad.count_edge_pairs(3, test), one);
    }
}
