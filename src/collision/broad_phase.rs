//! Broad phase: which point–edge (and edge–edge) pairs can touch this step.
//!
//! Every edge's swept box (its endpoints at the start and end of the step, inflated by
//! the margin) is entered into a uniform grid, hashed into a table and stored by
//! counting sort in reused buffers; each point's swept segment then queries the cells
//! it covers. Cost grows near-linearly with the number of edges in a pile. Brute force
//! (every pair) stays available for testing. Large builds and queries are shared
//! between threads, with the same grid and pairs on any count.

use bevy::math::DVec2;
use bevy::prelude::Reflect;

use crate::model::Edge;
use crate::parallel::{in_runs, run_each, split_at_cuts};

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

/// Cells `x0..=x1` by `y0..=y1`: 32-bit, so a build reads and writes half the bytes.
type CellRange = (i32, i32, i32, i32);

/// Scaled coordinates at or beyond this many cells from the origin are not entered in
/// the grid (the box is tested against everything): every cell index, and every
/// difference of two, fits in an `i32`.
const CELL_LIMIT: f64 = (1u32 << 29) as f64;

/// `v.floor() as i32` for `|v| <` [`CELL_LIMIT`], without the library call `floor` is
/// on baseline x86-64 (it was a tenth of a step in free fall).
fn floor_to_i32(v: f64) -> i32 {
    let truncated = v as i32;
    truncated - i32::from((truncated as f64) > v)
}

fn hash(ix: i64, iy: i64, mask: usize) -> usize {
    ((ix.wrapping_mul(73_856_093) ^ iy.wrapping_mul(19_349_663)) as u64 as usize) & mask
}

/// Below this many edges the grid is built on one thread.
const PARALLEL_BUILD: usize = 16_384;

/// Edges whose box sizes are summed together before the blocks' sums are added, in
/// order: the cell size is the same on any thread count.
const EXTENT_BLOCK: usize = 4096;

/// A placeholder box, overwritten before it is read.
const EMPTY: Aabb = Aabb {
    min: DVec2::ZERO,
    max: DVec2::ZERO,
};

/// The cells of a box at `inverse_cell` cells per unit, or `None` when it is better
/// tested against everything than entered in the grid.
fn cells_of(b: &Aabb, inverse_cell: f64) -> Option<CellRange> {
    let scaled = [b.min.x, b.min.y, b.max.x, b.max.y].map(|v| v * inverse_cell);
    // NaN fails the comparison too.
    let inside = scaled
        .iter()
        .fold(true, |inside, v| inside & (v.abs() < CELL_LIMIT));
    if !inside {
        return None;
    }
    let [x0, y0, x1, y1] = scaled.map(floor_to_i32);
    let cells = i64::from(x1 - x0 + 1) * i64::from(y1 - y0 + 1);
    (cells <= MAX_CELLS_PER_EDGE).then_some((x0, y0, x1, y1))
}

/// The swept boxes of `edges[start..]` into `boxes`, and each block of
/// [`EXTENT_BLOCK`] edges' summed box size to `sum`, in order (`start` a multiple of
/// the block).
fn fill_boxes(
    edges: &[Edge],
    position: &[DVec2],
    displacement: Option<&[DVec2]>,
    margin: f64,
    start: usize,
    boxes: &mut [Aabb],
    sum: &mut dyn FnMut(f64),
) {
    for (block, boxes) in boxes.chunks_mut(EXTENT_BLOCK).enumerate() {
        let mut extent = 0.0;
        for (k, slot) in boxes.iter_mut().enumerate() {
            let e = &edges[start + block * EXTENT_BLOCK + k];
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
            *slot = b;
        }
        sum(extent);
    }
}

/// The cells of `boxes[start..]` into `cells`, the oversized ones' indices appended to
/// `oversized`: the range holding every cell.
fn fill_cells(
    boxes: &[Aabb],
    inverse_cell: f64,
    start: usize,
    cells: &mut [Option<CellRange>],
    oversized: &mut Vec<u32>,
) -> Option<CellRange> {
    let mut bounds: Option<CellRange> = None;
    for (k, slot) in cells.iter_mut().enumerate() {
        *slot = cells_of(&boxes[start + k], inverse_cell);
        match (*slot, &mut bounds) {
            (None, _) => oversized.push((start + k) as u32),
            (Some(c), None) => bounds = Some(c),
            (Some(c), Some(b)) => *b = union(*b, c),
        }
    }
    bounds
}

/// The smallest cell range holding both.
fn union(a: CellRange, b: CellRange) -> CellRange {
    (a.0.min(b.0), a.1.min(b.1), a.2.max(b.2), a.3.max(b.3))
}

/// A grid of at most this many cells per edge is indexed directly, not hashed.
const DENSE_CELLS_PER_EDGE: i64 = 8;

impl BroadPhase {
    /// The bucket of a cell (inside the dense grid, when there is one).
    fn bucket(&self, ix: i32, iy: i32) -> usize {
        let (ix, iy) = (i64::from(ix), i64::from(iy));
        match self.dense {
            Some((x0, y0, x1, _)) => {
                let (x0, y0, x1) = (i64::from(x0), i64::from(y0), i64::from(x1));
                ((iy - y0) * (x1 - x0 + 1) + (ix - x0)) as usize
            }
            None => hash(ix, iy, self.mask),
        }
    }

    /// The cells of a box, or `None` when it is better tested against everything than
    /// entered in the grid.
    fn cells(&self, b: &Aabb) -> Option<CellRange> {
        cells_of(b, self.inverse_cell)
    }

    /// Build the grid over every edge's swept box: positions `x`, end positions
    /// `x + d` (`None`: not moving), inflated by `margin`. With `threads` above one and
    /// at least `PARALLEL_BUILD` edges, the boxes, their cells and (in a dense grid)
    /// the counting sort are shared between threads: the boxes and cells by contiguous
    /// runs of edges, the sort by bands of grid rows, each thread entering every edge's
    /// cells of its own band in edge order. The grid is the same whatever the count.
    pub fn build(
        &mut self,
        edges: &[Edge],
        position: &[DVec2],
        displacement: Option<&[DVec2]>,
        margin: f64,
        threads: usize,
    ) {
        let count = edges.len();
        let threads = if count >= PARALLEL_BUILD {
            threads.max(1)
        } else {
            1
        };
        // The boxes, and their sizes summed block by block (the same sum on any count).
        self.edge_boxes.clear();
        self.edge_boxes.resize(count, EMPTY);
        let mut extent = 0.0;
        let fill = |start: usize, boxes: &mut [Aabb], sum: &mut dyn FnMut(f64)| {
            fill_boxes(edges, position, displacement, margin, start, boxes, sum);
        };
        if threads == 1 {
            fill(0, &mut self.edge_boxes, &mut |s| extent += s);
        } else {
            let sums = in_runs(
                &mut self.edge_boxes,
                threads,
                EXTENT_BLOCK,
                |start, boxes| {
                    let mut sums = Vec::with_capacity(boxes.len().div_ceil(EXTENT_BLOCK));
                    fill(start, boxes, &mut |s| sums.push(s));
                    sums
                },
            );
            sums.into_iter().flatten().for_each(|s| extent += s);
        }
        // A cell about the size of a typical edge's box.
        self.inverse_cell = 1.0 / (extent / count.max(1) as f64).max(1e-9);
        let inverse_cell = self.inverse_cell;
        self.edge_cells.clear();
        self.edge_cells.resize(count, None);
        self.oversized.clear();
        let boxes = &self.edge_boxes;
        let bounds = if threads == 1 {
            fill_cells(
                boxes,
                inverse_cell,
                0,
                &mut self.edge_cells,
                &mut self.oversized,
            )
        } else {
            let runs = in_runs(&mut self.edge_cells, threads, 1, |start, cells| {
                let mut oversized = Vec::new();
                let bounds = fill_cells(boxes, inverse_cell, start, cells, &mut oversized);
                (bounds, oversized)
            });
            let mut bounds: Option<CellRange> = None;
            for (b, oversized) in runs {
                self.oversized.extend_from_slice(&oversized);
                bounds = match (bounds, b) {
                    (Some(a), Some(b)) => Some(union(a, b)),
                    (a, b) => a.or(b),
                };
            }
            bounds
        };
        self.dense = bounds.filter(|&(x0, y0, x1, y1)| {
            let cells = i64::from(x1 - x0 + 1) * i64::from(y1 - y0 + 1);
            cells <= DENSE_CELLS_PER_EDGE.saturating_mul(count.max(1) as i64)
        });
        let table = match self.dense {
            Some((x0, y0, x1, y1)) => ((x1 - x0 + 1) * (y1 - y0 + 1)) as usize,
            None => (2 * count.max(1)).next_power_of_two(),
        };
        self.mask = table.next_power_of_two() - 1;
        match self.dense {
            Some(grid) if threads > 1 => self.sort_in_bands(grid, table, threads),
            _ => self.sort_entries(table),
        }
    }

    /// Count, prefix-sum, fill: a counting sort of (bucket, edge) entries.
    fn sort_entries(&mut self, table: usize) {
        self.bucket_start.clear();
        self.bucket_start.resize(table + 1, 0);
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

    /// [`BroadPhase::sort_entries`] for the dense grid `grid`, on `threads` threads:
    /// each counts, sums and fills the buckets of its own band of grid rows, so each
    /// writes its own runs of the arrays and the result is the one-thread one.
    fn sort_in_bands(&mut self, grid: CellRange, table: usize, threads: usize) {
        let (x0, y0, x1, y1) = grid;
        let (width, rows) = ((x1 - x0 + 1) as usize, (y1 - y0 + 1) as usize);
        let threads = threads.min(rows);
        // Band t: grid rows rows·t/T to rows·(t+1)/T, whose buckets start at first(t).
        let first_row = |t: usize| rows * t / threads;
        let bands: Vec<usize> = (0..=threads).map(|t| first_row(t) * width).collect();
        let cells = &self.edge_cells;
        // Every edge's cells in band t, in edge order: (bucket, edge).
        let enter = |t: usize, visit: &mut dyn FnMut(usize, u32)| {
            let (from, to) = (y0 + first_row(t) as i32, y0 + first_row(t + 1) as i32);
            for (k, c) in cells.iter().enumerate() {
                let Some((cx0, cy0, cx1, cy1)) = *c else {
                    continue;
                };
                for iy in cy0.max(from)..=cy1.min(to - 1) {
                    let row = (iy - y0) as usize * width;
                    for ix in cx0..=cx1 {
                        visit(row + (ix - x0) as usize, k as u32);
                    }
                }
            }
        };
        // Counts into bucket_start[b + 1], then each band's running sums from 0.
        self.bucket_start.clear();
        self.bucket_start.resize(table + 1, 0);
        let parts = split_at_cuts(&mut self.bucket_start[1..], &bands);
        let totals = run_each(parts, |t, counts| {
            enter(t, &mut |bucket, _| counts[bucket - bands[t]] += 1);
            let mut sum = 0;
            for c in counts.iter_mut() {
                sum += *c;
                *c = sum;
            }
            sum
        });
        // Each band's sums moved up by the bands' before it.
        let mut offsets = Vec::with_capacity(threads);
        let mut total = 0;
        for t in totals {
            offsets.push(total);
            total += t;
        }
        let parts = split_at_cuts(&mut self.bucket_start[1..], &bands);
        run_each(parts, |t, sums| {
            sums.iter_mut().for_each(|s| *s += offsets[t])
        });
        // Fill: each band with its own cursors into its own run of the entries.
        self.entries.clear();
        self.entries.resize(total as usize, 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.bucket_start[..table]);
        let starts: Vec<usize> = bands
            .iter()
            .map(|&b| self.bucket_start[b] as usize)
            .collect();
        let cursors = split_at_cuts(&mut self.cursor, &bands);
        let runs = split_at_cuts(&mut self.entries, &starts);
        let parts: Vec<_> = cursors.into_iter().zip(runs).collect();
        run_each(parts, |t, (cursor, run)| {
            enter(t, &mut |bucket, k| {
                let slot = &mut cursor[bucket - bands[t]];
                run[*slot as usize - starts[t]] = k;
                *slot += 1;
            });
        });
    }

    /// Visit each edge from `first` on whose box overlaps `query` (its cells `cells`)
    /// once, in a fixed order. `stamp` must differ between consecutive queries on
    /// `seen` and be non-zero.
    fn visit_cells(
        &self,
        query: &Aabb,
        cells: Option<CellRange>,
        (seen, stamp): (&mut [u32], u32),
        first: u32,
        mut visit: impl FnMut(u32),
    ) {
        let Some((x0, y0, x1, y1)) = cells else {
            // A huge query: test every edge.
            for k in first..self.edge_boxes.len() as u32 {
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
                let run =
                    self.bucket_start[bucket] as usize..self.bucket_start[bucket + 1] as usize;
                let run = &self.entries[run];
                // A bucket's edges are in ascending order (entered in edge order).
                for &k in &run[run.partition_point(|&k| k < first)..] {
                    if seen[k as usize] != stamp {
                        seen[k as usize] = stamp;
                        if self.edge_boxes[k as usize].overlaps(query) {
                            visit(k);
                        }
                    }
                }
            }
        }
        let oversized = &self.oversized;
        for &k in &oversized[oversized.partition_point(|&k| k < first)..] {
            if self.edge_boxes[k as usize].overlaps(query) {
                visit(k);
            }
        }
    }

    /// The boxes of the last build, one per edge (each entered in the grid or tested
    /// against every query).
    pub fn boxes(&self) -> &[Aabb] {
        &self.edge_boxes
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
        self.query_shares(threads, n, |i| i, position, displacement, keep, pairs);
    }

    /// The grid queries of `n` points, the `k`th being point `point(k)` (ascending), in
    /// shares on `threads` threads, appended to `pairs` in order.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn query_shares(
        &mut self,
        threads: usize,
        n: usize,
        point: impl Fn(usize) -> usize + Sync,
        position: &[DVec2],
        displacement: &[DVec2],
        keep: impl Fn(u32, u32) -> bool + Sync,
        pairs: &mut Vec<(u32, u32)>,
    ) {
        self.reset_seen();
        self.in_shares(
            n,
            threads,
            pairs,
            |this, shares, seen, pairs| {
                let points = shares.map(&point);
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
        let mut parts = vec![(0..n / threads, &mut seen[..], &mut *pairs)];
        for QueryLane { range, seen, pairs } in lanes.iter_mut() {
            parts.push((range.clone(), &mut seen[..], pairs));
        }
        let this = &*self;
        let results = run_each(parts, |_, (range, seen, pairs)| {
            work(this, range, seen, pairs)
        });
        for lane in &lanes {
            pairs.extend_from_slice(&lane.pairs);
        }
        self.seen = seen;
        self.lanes = lanes;
        let mut results = results.into_iter();
        let first = results.next().expect("the first share");
        results.fold(first, combine)
    }

    /// The grid queries of the points in `points`, stamped in `seen`.
    fn query_points(
        &self,
        points: impl Iterator<Item = usize>,
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
            self.visit_cells(&query, cells, (seen, point + 1), 0, |k| {
                if keep(point, k) {
                    pairs.push((point, k));
                }
            });
        }
    }

    /// Over every pair of edges (j < k) whose boxes overlap — with `moving`, every such
    /// pair with at least one moving edge, queried from it — how many `test` holds for,
    /// and the smallest such (j, k): a pair that does not depend on the grid. With
    /// `threads` above one and enough edges, contiguous ranges of j are tested on that
    /// many threads: the same count and the same first pair whatever the count. Call
    /// [`BroadPhase::build`] first.
    pub fn count_edge_pairs(
        &mut self,
        threads: usize,
        moving: Option<&[bool]>,
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
            |this, range, seen, _| this.count_edges(range, moving, &test, seen),
            |(count, found), (c, f)| {
                let first = match (found, f) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                };
                (count + c, first)
            },
        )
    }

    /// [`BroadPhase::count_edge_pairs`] over the edges `range` as the first of a pair.
    fn count_edges(
        &self,
        range: std::ops::Range<usize>,
        moving: Option<&[bool]>,
        test: &(impl Fn(u32, u32) -> bool + Sync),
        seen: &mut [u32],
    ) -> (usize, Option<(u32, u32)>) {
        let (mut count, mut first) = (0, None);
        let moves = |e: u32| moving.is_none_or(|m| m[e as usize]);
        for j in range.map(|j| j as u32).filter(|&j| moves(j)) {
            let query = self.edge_boxes[j as usize];
            let cells = self.edge_cells[j as usize];
            // All pairs: from the lower edge. Moving pairs: from a moving edge, a pair
            // of two from the lower.
            let from = if moving.is_some() { 0 } else { j + 1 };
            self.visit_cells(&query, cells, (seen, j + 1), from, |k| {
                let counted = k != j && (!moves(k) || j < k);
                if counted && test(j, k) {
                    count += 1;
                    let pair = (j.min(k), j.max(k));
                    first = Some(first.map_or(pair, |f: (u32, u32)| f.min(pair)));
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
                    self.visit_cells(&query, cells, (&mut seen, j + 1), j + 1, |k| {
                        if keep(j, k) {
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
            broad.build(&edges, &position, Some(&displacement), 0.004, 1);
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
        broad.build(&edges, &position, Some(&displacement), 0.004, 1);
        let test = |j: u32, k: u32| (j + k).is_multiple_of(3);
        let mut listed = Vec::new();
        broad.edge_edge_pairs(BroadPhaseMethod::Grid, test, &mut listed);
        let one = broad.count_edge_pairs(1, None, test);
        assert!(one.0 > 1000, "{one:?}");
        assert_eq!(one, (listed.len(), listed.iter().min().copied()));
        assert_eq!(broad.count_edge_pairs(2, None, test), one);
        assert_eq!(broad.count_edge_pairs(3, None, test), one);
    }

    #[test]
    fn building_on_more_threads_gives_the_same_grid() {
        let mut rng = StdRng::seed_from_u64(9);
        let (mut position, displacement, edges) = random_scene(&mut rng, 1000);
        assert!(edges.len() >= PARALLEL_BUILD, "{} edges", edges.len());
        let grid = |b: &BroadPhase| {
            (
                b.inverse_cell.to_bits(),
                b.dense,
                b.mask,
                b.bucket_start.clone(),
                b.entries.clone(),
                b.edge_cells.clone(),
                b.oversized.clone(),
            )
        };
        for spread in [false, true] {
            if spread {
                // A few strands far away: the cells no longer fit a dense grid.
                for p in position.iter_mut().take(200) {
                    *p *= 1000.0;
                }
            }
            let mut one = BroadPhase::default();
            one.build(&edges, &position, Some(&displacement), 0.004, 1);
            assert_eq!(one.dense.is_none(), spread);
            let mut pairs_one = Vec::new();
            one.point_edge_pairs(
                BroadPhaseMethod::Grid,
                1,
                &position,
                &displacement,
                |p, k| edges[k as usize].a != p && edges[k as usize].b != p,
                &mut pairs_one,
            );
            assert!(pairs_one.len() > 1000);
            for threads in [2, 3, 5] {
                let mut many = BroadPhase::default();
                many.build(&edges, &position, Some(&displacement), 0.004, threads);
                assert_eq!(
                    grid(&many),
                    grid(&one),
                    "{threads} threads, spread {spread}"
                );
            }
        }
    }
}
