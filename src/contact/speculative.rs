//! Speculative contacts: which point–edge pairs of a step become rows of the contact
//! solve, and what each row asks. Box2D's speculative contacts, for strands: a pair
//! the step's motion brings within reach is met inside the projection, before any
//! impulse, both sides moving, so landings and strands resting on strands keep every
//! edge exact.
//!
//! A pure kernel: the broad phase's pairs (grouped by point) in, rows out.

use bevy::math::DVec2;

use super::rows::ContactRow;
use crate::model::geometry::closest_on_segment;
use crate::model::{Edge, PointEdgePair};
use crate::parallel::run_each;

/// What the rows of a step ask.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeculationSettings {
    /// The cushion `h`: a pair approaching from farther ends the step this far apart.
    pub thickness: f64,
    /// A pair inside the cushion but at least this far apart may stay where it is; a
    /// closer one is pushed out to it by a tenth of the overlap per step.
    pub keep: f64,
    /// Pairs that start and would end the step farther apart than this get no row.
    pub reach: f64,
    /// Coulomb friction coefficient of the rows.
    pub friction: f64,
    /// The direction of gravity (unit, or zero without gravity): rows are ordered from
    /// the lowest point up, so the sweeps carry a pile's weight down to what holds it
    /// within one pass.
    pub down: DVec2,
}

/// Buffers of [`speculative_rows`], reused from step to step.
#[derive(Clone, Debug, Default)]
pub struct SpeculationScratch {
    candidates: Vec<Candidate>,
    /// Each point's pairs (first, end) with its height.
    points: Vec<(f64, u32, u32)>,
    /// The other threads' buffers.
    lanes: Vec<Lane>,
}

/// One other thread's candidates, rows and keys.
#[derive(Clone, Debug, Default)]
struct Lane {
    candidates: Vec<Candidate>,
    rows: Vec<ContactRow>,
    keys: Vec<(u32, u32, u32)>,
}

/// Below this many points with pairs the rows are built on one thread: a point's rows
/// take a fraction of a microsecond, starting a thread tens.
const PARALLEL_POINTS: usize = 2048;

/// A key's second half for a row that is not its point's nearest on its strand: the
/// edge, with this bit set (the nearest row of a strand is keyed by the strand).
pub const EDGE_KEY: u32 = 1 << 31;

/// A candidate row of the current point.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    edge: u32,
    strand: u32,
    alpha: f64,
    gap: f64,
    normal: DVec2,
}

/// Two rows of one point on one strand are kept only where their normals differ by
/// more than 45° (the point sits in a corner): nearer rows of the same strand are the
/// same contact seen from two edges that meet there, and would only slow the sweeps.
const CORNER_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The rows of the step for `pairs` (point, edge), grouped by point as the broad phase
/// gives them, the lowest point's first. For each point and each strand within reach,
/// the nearest edge gives one row; another edge of that strand gives one only in a
/// corner. Each row's key is (point, strand) or (point, [`EDGE_KEY`] | edge), for warm
/// starts, followed by its edge. With `threads` above one and enough points, runs of
/// points are built on that many threads and their rows appended in order: the same
/// rows whatever the count.
#[allow(clippy::too_many_arguments)]
pub fn speculative_rows(
    pairs: &[(u32, u32)],
    edges: &[Edge],
    position: &[DVec2],
    velocity: &[DVec2],
    dt: f64,
    settings: &SpeculationSettings,
    threads: usize,
    scratch: &mut SpeculationScratch,
    rows: &mut Vec<ContactRow>,
    keys: &mut Vec<(u32, u32, u32)>,
) {
    rows.clear();
    keys.clear();
    let SpeculationScratch {
        candidates,
        points,
        lanes,
    } = scratch;
    points.clear();
    let mut start = 0;
    while start < pairs.len() {
        let p = pairs[start].0;
        let end = start + pairs[start..].iter().take_while(|t| t.0 == p).count();
        let height = -settings.down.dot(position[p as usize]);
        points.push((height, start as u32, end as u32));
        start = end;
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let build = |run: &[(f64, u32, u32)],
                 candidates: &mut Vec<Candidate>,
                 rows: &mut Vec<ContactRow>,
                 keys: &mut Vec<(u32, u32, u32)>| {
        for &(_, start, end) in run {
            let pairs = &pairs[start as usize..end as usize];
            point_rows(
                pairs, edges, position, velocity, dt, settings, candidates, rows, keys,
            );
        }
    };
    let threads = if points.len() >= PARALLEL_POINTS {
        threads.max(1)
    } else {
        1
    };
    if threads == 1 {
        build(points, candidates, rows, keys);
        return;
    }
    lanes.resize_with(threads - 1, Default::default);
    let n = points.len();
    let mut parts = vec![(&points[..n / threads], candidates, &mut *rows, &mut *keys)];
    for (t, lane) in lanes.iter_mut().enumerate() {
        lane.rows.clear();
        lane.keys.clear();
        let run = &points[n * (t + 1) / threads..n * (t + 2) / threads];
        parts.push((run, &mut lane.candidates, &mut lane.rows, &mut lane.keys));
    }
    run_each(parts, |_, (run, candidates, rows, keys)| {
        build(run, candidates, rows, keys)
    });
    for lane in lanes.iter() {
        rows.extend_from_slice(&lane.rows);
        keys.extend_from_slice(&lane.keys);
    }
}

/// The rows of one point, from its `pairs`.
#[allow(clippy::too_many_arguments)]
fn point_rows(
    pairs: &[(u32, u32)],
    edges: &[Edge],
    position: &[DVec2],
    velocity: &[DVec2],
    dt: f64,
    settings: &SpeculationSettings,
    candidates: &mut Vec<Candidate>,
    rows: &mut Vec<ContactRow>,
    keys: &mut Vec<(u32, u32, u32)>,
) {
    let p = pairs[0].0;
    candidates.clear();
    for &(_, k) in pairs {
        let e = &edges[k as usize];
        let (q, r, x) = (
            position[e.a as usize],
            position[e.b as usize],
            position[p as usize],
        );
        let (alpha, gap) = closest_on_segment(x, q, r);
        if gap <= 0.0 {
            continue; // on the edge: the collision stage decides its side
        }
        let normal = (x - q.lerp(r, alpha)) / gap;
        let relative =
            velocity[p as usize] - velocity[e.a as usize].lerp(velocity[e.b as usize], alpha);
        if gap.min(gap + dt * normal.dot(relative)) >= settings.reach {
            continue; // starts and would end the step out of reach
        }
        candidates.push(Candidate {
            edge: k,
            strand: e.strand,
            alpha,
            gap,
            normal,
        });
    }
    candidates.sort_unstable_by(|a, b| a.strand.cmp(&b.strand).then(a.gap.total_cmp(&b.gap)));
    let mut first = 0;
    while first < candidates.len() {
        let strand = candidates[first].strand;
        let last = first
            + candidates[first..]
                .iter()
                .take_while(|c| c.strand == strand)
                .count();
        for i in first..last {
            let c = candidates[i];
            let corner = candidates[first..i]
                .iter()
                .all(|kept| kept.normal.dot(c.normal) < CORNER_COS);
            if i > first && !corner {
                continue;
            }
            let e = &edges[c.edge as usize];
            let pair = PointEdgePair {
                p: p as usize,
                q: e.a as usize,
                r: e.b as usize,
                alpha: c.alpha,
            };
            let mut row = ContactRow::point_edge(pair, c.normal, velocity);
            row.target = target(c.gap, settings, dt);
            row.friction = settings.friction;
            rows.push(row);
            keys.push((
                p,
                if i == first {
                    strand
                } else {
                    EDGE_KEY | c.edge
                },
                c.edge,
            ));
        }
        first = last;
    }
}

/// The smallest relative normal velocity a pair `gap` apart may end the step with:
/// from outside the cushion, just enough to end it a thickness apart; inside it, no
/// approach; closer than `keep`, away by a tenth of the overlap per step, so resting
/// contact settles without popping.
fn target(gap: f64, settings: &SpeculationSettings, dt: f64) -> f64 {
    if gap >= settings.thickness {
        (settings.thickness - gap) / dt
    } else if gap >= settings.keep {
        0.0
    } else {
        0.1 * (settings.keep - gap) / dt
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> SpeculationSettings {
        SpeculationSettings {
            thickness: 0.004,
            keep: 0.002,
            reach: 0.008,
            friction: 0.3,
            down: DVec2::NEG_Y,
        }
    }

    fn edge(a: u32, b: u32, strand: u32, position: &[DVec2]) -> Edge {
        Edge {
            strand,
            ..Edge::new(a, b, position[a as usize].distance(position[b as usize]))
        }
    }

    fn rows_for(
        pairs: &[(u32, u32)],
        edges: &[Edge],
        position: &[DVec2],
        velocity: &[DVec2],
    ) -> (Vec<ContactRow>, Vec<(u32, u32, u32)>) {
        let (mut rows, mut keys) = (Vec::new(), Vec::new());
        speculative_rows(
            pairs,
            edges,
            position,
            velocity,
            0.01,
            &settings(),
            1,
            &mut SpeculationScratch::default(),
            &mut rows,
            &mut keys,
        );
        (rows, keys)
    }

    #[test]
    fn two_threads_build_the_rows_of_one() {
        // 3 000 points each over its own strand's edge (most within reach), and paired with
        // the next strand's edge too (out of reach), given in point order.
        let (mut position, mut edges, mut pairs) = (Vec::new(), Vec::new(), Vec::new());
        let velocity: Vec<DVec2> = (0..9000)
            .map(|i| DVec2::new(0.0, -0.1 * (i % 7) as f64))
            .collect();
        for i in 0..3000u32 {
            let x = 0.03 * i as f64;
            let tilt = 0.001 * (i % 5) as f64;
            position.extend([
                DVec2::new(x + 0.001 * (i % 3) as f64, 0.001 * (i % 11) as f64),
                DVec2::new(x - 0.01, -0.004),
                DVec2::new(x + 0.01, -0.003 + tilt),
            ]);
        }
        for i in 0..3000u32 {
            edges.push(edge(3 * i + 1, 3 * i + 2, i, &position));
        }
        for i in 0..3000u32 {
            pairs.push((3 * i, i));
            if i + 1 < 3000 {
                pairs.push((3 * i, i + 1));
            }
        }
        let build = |threads| {
            let (mut rows, mut keys) = (Vec::new(), Vec::new());
            let mut scratch = SpeculationScratch::default();
            // Twice with the same buffers: the lanes' rows from the first are not kept.
            for _ in 0..2 {
                speculative_rows(
                    &pairs,
                    &edges,
                    &position,
                    &velocity,
                    0.01,
                    &settings(),
                    threads,
                    &mut scratch,
                    &mut rows,
                    &mut keys,
                );
            }
            (rows, keys)
        };
        let one = build(1);
        assert!(one.0.len() > 1500, "{}", one.0.len());
        assert_eq!(build(2), one);
        assert_eq!(build(3), one);
    }

    #[test]
    fn a_point_over_the_local_of_a_straight_strand_gets_one_row() {
        // Point 0 just above particle 2, where edges 1–2 and 2–3 of a flat strand meet.
        let position = vec![
            DVec2::new(0.0, 0.003),
            DVec2::new(-0.02, 0.0),
            DVec2::new(0.0, 0.0),
            DVec2::new(0.02, 0.0),
        ];
        let edges = [edge(1, 2, 7, &position), edge(2, 3, 7, &position)];
        let velocity = vec![DVec2::ZERO; 4];
        let (rows, keys) = rows_for(&[(0, 0), (0, 1)], &edges, &position, &velocity);
        assert_eq!(rows.len(), 1);
        assert_eq!(keys[0].0, 0);
        assert_eq!(keys[0].1, 7, "keyed by the strand");
        assert!((rows[0].normal - DVec2::Y).length() < 1e-12);
    }

    #[test]
    fn a_point_in_a_corner_gets_a_row_against_each_wall() {
        let position = vec![
            DVec2::new(0.003, 0.003),
            DVec2::new(0.0, 0.5),
            DVec2::new(0.0, 0.0),
            DVec2::new(0.5, 0.0),
        ];
        let edges = [edge(1, 2, 0, &position), edge(2, 3, 0, &position)];
        let velocity = vec![DVec2::ZERO; 4];
        let (rows, keys) = rows_for(&[(0, 0), (0, 1)], &edges, &position, &velocity);
        assert_eq!(rows.len(), 2);
        assert_eq!(keys[0].1, 0);
        assert_eq!(keys[1].1, EDGE_KEY | keys[1].2);
        assert!(rows[0].normal.dot(rows[1].normal).abs() < 1e-12);
    }

    #[test]
    fn rows_come_lowest_point_first_and_ask_for_the_cushion() {
        // Three points over a floor: 0 high and approaching, 1 inside the cushion, 2
        // deep inside it; one far point with no row.
        let position = vec![
            DVec2::new(0.1, 0.006),
            DVec2::new(0.2, 0.003),
            DVec2::new(0.3, 0.001),
            DVec2::new(0.4, 0.5),
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
        ];
        let edges = [edge(4, 5, 1, &position)];
        let mut velocity = vec![DVec2::ZERO; 6];
        velocity[0] = DVec2::new(0.0, -1.0);
        let pairs = [(0, 0), (1, 0), (2, 0), (3, 0)];
        let (rows, keys) = rows_for(&pairs, &edges, &position, &velocity);
        let points: Vec<u32> = keys.iter().map(|k| k.0).collect();
        assert_eq!(points, [2, 1, 0]);
        let dt = 0.01;
        // Deep inside: out to `keep` by a tenth of the overlap per step.
        assert!((rows[0].target - 0.1 * (0.002 - 0.001) / dt).abs() < 1e-12);
        // Inside the cushion but beyond `keep`: no approach.
        assert_eq!(rows[1].target, 0.0);
        // Approaching from outside: end the step a thickness apart.
        assert!((rows[2].target - (0.004 - 0.006) / dt).abs() < 1e-12);
        assert!(rows.iter().all(|r| r.friction == 0.3));
    }
}
