//! Which sleeping units something moving will come within reach of this tick.
//!
//! A moving particle sweeps the segment from where it is to where its velocity takes
//! it by the tick's end; a moving edge sweeps the quadrilateral between its two
//! positions. A target (sleeping) unit is reached when one of its edges comes within
//! `reach` of a moving particle's sweep, or one of its particles within `reach` of a
//! moving edge's sweep: the distance between two segments that do not cross is taken
//! at an endpoint of one of them, so the two tests together find every approach. Both
//! go through the broad phase: the target edges' boxes queried with the moving points'
//! sweeps, the moving edges' swept boxes with the target points.

use bevy::math::DVec2;

use super::units::NO_UNIT;
use crate::collision::broad_phase::{BroadPhase, BroadPhaseMethod};
use crate::model::Edge;
use crate::model::geometry::{closest_on_segment, segment_distance};

/// What the test reads.
pub struct ReachInput<'a> {
    /// Every edge.
    pub edges: &'a [Edge],
    /// The unit of each particle ([`NO_UNIT`] for walls).
    pub unit_of: &'a [u32],
    /// Whether each unit is a target (asleep, or about to be).
    pub target: &'a [bool],
    /// Whether each particle moves (faster than the sleep speed, outside the targets).
    pub moving: &'a [bool],
    /// Positions.
    pub position: &'a [DVec2],
    /// How far each particle moves by the tick's end.
    pub displacement: &'a [DVec2],
    /// How near counts as reached.
    pub reach: f64,
    /// Threads the broad phase may use.
    pub threads: usize,
}

/// Reused buffers.
#[derive(Default, Clone, Debug)]
pub struct ReachScratch {
    targets: BroadPhase,
    movers: BroadPhase,
    target_edges: Vec<Edge>,
    moving_edges: Vec<Edge>,
    points: Vec<DVec2>,
    sweeps: Vec<DVec2>,
    index: Vec<u32>,
    still: Vec<DVec2>,
    linked: Vec<bool>,
    pairs: Vec<(u32, u32)>,
}

/// Whether unit `u` is a target, for a particle's unit.
fn is_target(input: &ReachInput, unit: u32) -> bool {
    unit != NO_UNIT && input.target[unit as usize]
}

/// Set `reached[u]` for every target unit something moving comes within reach of.
pub fn find_reached(input: &ReachInput, scratch: &mut ReachScratch, reached: &mut [bool]) {
    let n = input.position.len();
    if !input.moving.iter().any(|&m| m) {
        return;
    }
    let unit = |i: u32| input.unit_of[i as usize];
    let moves = |i: u32| input.moving[i as usize];

    // The targets' edges; a target particle on no edge enters as an edge of one point.
    scratch.linked.clear();
    scratch.linked.resize(n, false);
    scratch.target_edges.clear();
    scratch.moving_edges.clear();
    for e in input.edges {
        if is_target(input, unit(e.a)) || is_target(input, unit(e.b)) {
            scratch.target_edges.push(*e);
            scratch.linked[e.a as usize] = true;
            scratch.linked[e.b as usize] = true;
            // A target's edge can move only as a despawned strand's "moves": where it
            // lay lets go of what rested on it.
            if moves(e.a) || moves(e.b) {
                scratch.moving_edges.push(*e);
            }
        } else if moves(e.a) || moves(e.b) {
            scratch.moving_edges.push(*e);
        }
    }
    for i in 0..n as u32 {
        if is_target(input, unit(i)) && !scratch.linked[i as usize] {
            scratch.target_edges.push(Edge {
                b: i,
                ..point_edge(i)
            });
        }
    }
    if scratch.target_edges.is_empty() {
        return;
    }

    // Moving points against the target edges.
    scratch.points.clear();
    scratch.sweeps.clear();
    scratch.index.clear();
    for i in (0..n).filter(|&i| input.moving[i]) {
        scratch.points.push(input.position[i]);
        scratch.sweeps.push(input.displacement[i]);
        scratch.index.push(i as u32);
    }
    scratch.targets.build(
        &scratch.target_edges,
        input.position,
        None,
        input.reach,
        input.threads,
    );
    scratch.pairs.clear();
    scratch.targets.point_edge_pairs(
        BroadPhaseMethod::Grid,
        input.threads,
        &scratch.points,
        &scratch.sweeps,
        |_, _| true,
        &mut scratch.pairs,
    );
    for &(p, k) in &scratch.pairs {
        let e = &scratch.target_edges[k as usize];
        let u = unit(e.a).min(unit(e.b)) as usize;
        if reached[u] {
            continue;
        }
        let (start, sweep) = (scratch.points[p as usize], scratch.sweeps[p as usize]);
        let (a, b) = (input.position[e.a as usize], input.position[e.b as usize]);
        if segment_distance(start, start + sweep, a, b) <= input.reach {
            reached[u] = true;
        }
    }

    // Target points against the moving edges' sweeps.
    if scratch.moving_edges.is_empty() {
        return;
    }
    scratch.points.clear();
    scratch.index.clear();
    for i in 0..n as u32 {
        if is_target(input, unit(i)) {
            scratch.points.push(input.position[i as usize]);
            scratch.index.push(i);
        }
    }
    scratch.still.clear();
    scratch.still.resize(scratch.points.len(), DVec2::ZERO);
    scratch.movers.build(
        &scratch.moving_edges,
        input.position,
        Some(input.displacement),
        input.reach,
        input.threads,
    );
    scratch.pairs.clear();
    scratch.movers.point_edge_pairs(
        BroadPhaseMethod::Grid,
        input.threads,
        &scratch.points,
        &scratch.still,
        |_, _| true,
        &mut scratch.pairs,
    );
    for &(p, k) in &scratch.pairs {
        let u = unit(scratch.index[p as usize]) as usize;
        if reached[u] {
            continue;
        }
        let e = &scratch.moving_edges[k as usize];
        let (a, b) = (input.position[e.a as usize], input.position[e.b as usize]);
        let (da, db) = (
            input.displacement[e.a as usize],
            input.displacement[e.b as usize],
        );
        if quad_distance(scratch.points[p as usize], [a, b, b + db, a + da]) <= input.reach {
            reached[u] = true;
        }
    }
}

/// An edge of one point (a loose particle in the target grid).
fn point_edge(i: u32) -> Edge {
    Edge {
        a: i,
        b: i,
        rest_length: 0.0,
        strand: u32::MAX,
        is_static: true,
        constrained: false,
        spring: false,
        stiffness: 0.0,
        damping: 0.0,
        solid: false,
    }
}

/// Distance from `p` to the quadrilateral `q` (an edge's sweep, corners in order):
/// 0 inside either of its two triangles, else the distance to its nearest side.
pub fn quad_distance(p: DVec2, q: [DVec2; 4]) -> f64 {
    let inside = |a: DVec2, b: DVec2, c: DVec2| {
        // A flat triangle has no inside (its sides are measured below).
        if (b - a).perp_dot(c - a) == 0.0 {
            return false;
        }
        let (d1, d2, d3) = (
            (b - a).perp_dot(p - a),
            (c - b).perp_dot(p - b),
            (a - c).perp_dot(p - c),
        );
        (d1 >= 0.0 && d2 >= 0.0 && d3 >= 0.0) || (d1 <= 0.0 && d2 <= 0.0 && d3 <= 0.0)
    };
    if inside(q[0], q[1], q[2]) || inside(q[0], q[2], q[3]) {
        return 0.0;
    }
    (0..4)
        .map(|k| closest_on_segment(p, q[k], q[(k + 1) % 4]).1)
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(a: u32, b: u32) -> Edge {
        Edge {
            b,
            strand: 0,
            constrained: true,
            is_static: false,
            rest_length: 1.0,
            ..point_edge(a)
        }
    }

    /// Brute force: every target edge against every moving sweep, and every target
    /// point against every moving edge's sweep.
    fn brute(input: &ReachInput) -> Vec<bool> {
        let mut reached = vec![false; input.target.len()];
        let x = input.position;
        let d = input.displacement;
        let target = |i: u32| is_target(input, input.unit_of[i as usize]);
        for e in input.edges.iter().filter(|e| target(e.a)) {
            for p in (0..x.len()).filter(|&p| input.moving[p]) {
                let dist = segment_distance(x[p], x[p] + d[p], x[e.a as usize], x[e.b as usize]);
                if dist <= input.reach {
                    reached[input.unit_of[e.a as usize] as usize] = true;
                }
            }
        }
        let moving_edges = input
            .edges
            .iter()
            .filter(|e| input.moving[e.a as usize] || input.moving[e.b as usize]);
        for e in moving_edges {
            let (a, b) = (e.a as usize, e.b as usize);
            for p in (0..x.len() as u32).filter(|&p| target(p)) {
                let quad = [x[a], x[b], x[b] + d[b], x[a] + d[a]];
                if quad_distance(x[p as usize], quad) <= input.reach {
                    reached[input.unit_of[p as usize] as usize] = true;
                }
            }
        }
        reached
    }

    #[test]
    fn the_grid_finds_what_every_pair_finds() {
        // Twenty sleeping strands of four particles in a row of columns, and a moving
        // strand of three sweeping across some of them at many offsets.
        let mut position = Vec::new();
        let mut edges = Vec::new();
        let mut unit_of = Vec::new();
        for s in 0..20u32 {
            for k in 0..4u32 {
                position.push(DVec2::new(0.05 * f64::from(s), 0.02 * f64::from(k)));
                unit_of.push(s);
                if k > 0 {
                    edges.push(edge(4 * s + k - 1, 4 * s + k));
                }
            }
        }
        let mover = position.len() as u32;
        for k in 0..3u32 {
            position.push(DVec2::new(0.3 + 0.013 * f64::from(k), 0.2));
            unit_of.push(20);
            if k > 0 {
                edges.push(edge(mover + k - 1, mover + k));
            }
        }
        let mut target = vec![true; 21];
        target[20] = false;
        let mut moving = vec![false; position.len()];
        moving[mover as usize..].fill(true);
        let mut scratch = ReachScratch::default();
        for step in 0..40 {
            let angle = 0.1 * f64::from(step);
            let sweep = DVec2::new(angle.cos(), -1.0 - angle.sin()) * 0.1 * f64::from(step % 7);
            let mut displacement = vec![DVec2::ZERO; position.len()];
            displacement[mover as usize..].fill(sweep);
            let input = ReachInput {
                edges: &edges,
                unit_of: &unit_of,
                target: &target,
                moving: &moving,
                position: &position,
                displacement: &displacement,
                reach: 0.008,
                threads: 1,
            };
            let mut reached = vec![false; 21];
            find_reached(&input, &mut scratch, &mut reached);
            assert_eq!(reached, brute(&input), "sweep {sweep}");
        }
    }

    #[test]
    fn a_point_inside_a_sweep_is_reached_and_one_beside_it_is_not() {
        let quad = [
            DVec2::ZERO,
            DVec2::X,
            DVec2::new(1.0, -1.0),
            DVec2::new(0.0, -1.0),
        ];
        assert_eq!(quad_distance(DVec2::new(0.5, -0.5), quad), 0.0);
        // A sweep along its own line is flat: a point on that line but past its end is
        // as far as it is.
        let flat = [DVec2::ZERO, DVec2::X, DVec2::X, DVec2::ZERO];
        assert_eq!(quad_distance(DVec2::new(3.0, 0.0), flat), 2.0);
        assert!((quad_distance(DVec2::new(1.5, -0.5), quad) - 0.5).abs() < 1e-15);
    }
}
