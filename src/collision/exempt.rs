//! Exempt pairs: a point and an edge of its own strand that lie within a thickness of
//! each other along the strand, measured by rest lengths.
//!
//! A point is never collided against its own edges. Where an edge is no longer than
//! the thickness, that is not enough: the point's distance to the next edge along is at
//! most that edge's length, reached at the particle they share, so the pair sits at or
//! inside the cushion for good. Its row would push along the edge itself — the
//! direction the edge's constraint already fixes — and is either degenerate (an edge
//! exactly a thickness long, rounding deciding which side it lies on) or cannot be met
//! at all (a shorter one). Such pairs keep no cushion: a point is exempt from the
//! thickness of every edge with an end within a thickness of it along the strand. They
//! are still tested for crossing (continuous detection has no thickness), so a strand
//! cannot fold through itself at a joint. Where every edge is longer than the
//! thickness, nothing is exempt and every pair is what it was.

use crate::model::Edge;

/// The reach along the strand, in thicknesses. A little over one: a joint pair whose
/// gap is a small fraction of the thickness is as degenerate as one with none (its row
/// all but parallel to the edge, active whenever the joint bends), and an edge drawn
/// a thickness long must count whichever way its length rounded.
pub const REACH: f64 = 1.25;

/// The points within a thickness of each point along its strand (by rest lengths),
/// built from the edges.
#[derive(Clone, Debug, Default)]
pub struct Exempt {
    /// `near[start[p]..start[p + 1]]`: the points within reach of `p`, ascending;
    /// `start` is empty when no point has any.
    start: Vec<u32>,
    near: Vec<u32>,
    /// Each particle's edges (other end, rest length), by `adjacent_start`.
    adjacent: Vec<(u32, f64)>,
    adjacent_start: Vec<u32>,
    /// The walk's frontier and the particles it has reached, with their distance.
    stack: Vec<(u32, f64)>,
    reached: Vec<(u32, f64)>,
    /// The topology version and thickness of the last [`Exempt::update`].
    built_for: Option<(u64, u64)>,
}

impl Exempt {
    /// Build from `edges` over `particles` particles for `thickness`. Costs one pass
    /// over the edges when none is within the reach.
    pub fn build(&mut self, edges: &[Edge], particles: usize, thickness: f64) {
        self.built_for = None;
        self.start.clear();
        self.near.clear();
        let reach = thickness * REACH;
        if !edges.iter().any(|e| e.rest_length <= reach) {
            return;
        }
        self.adjacency(edges, particles);
        self.start.reserve(particles + 1);
        for p in 0..particles as u32 {
            self.start.push(self.near.len() as u32);
            self.walk(p, reach);
        }
        self.start.push(self.near.len() as u32);
    }

    /// [`Exempt::build`] unless the last update was for the same topology `version`
    /// (whose edges `edges` are) and `thickness`.
    pub fn update(&mut self, version: u64, edges: &[Edge], particles: usize, thickness: f64) {
        let key = Some((version, thickness.to_bits()));
        if self.built_for != key {
            self.build(edges, particles, thickness);
            self.built_for = key;
        }
    }

    /// Whether no point is exempt from any edge.
    pub fn is_empty(&self) -> bool {
        self.start.is_empty()
    }

    /// Whether point `p` is exempt from edge `e`.
    pub fn exempt(&self, p: u32, e: &Edge) -> bool {
        let Some(range) = self
            .start
            .get(p as usize)
            .zip(self.start.get(p as usize + 1))
        else {
            return false;
        };
        let near = &self.near[*range.0 as usize..*range.1 as usize];
        near.binary_search(&e.a).is_ok() || near.binary_search(&e.b).is_ok()
    }

    /// Each particle's edges, as a compressed list.
    fn adjacency(&mut self, edges: &[Edge], particles: usize) {
        self.adjacent_start.clear();
        self.adjacent_start.resize(particles + 1, 0);
        for e in edges {
            self.adjacent_start[e.a as usize + 1] += 1;
            self.adjacent_start[e.b as usize + 1] += 1;
        }
        for i in 0..particles {
            self.adjacent_start[i + 1] += self.adjacent_start[i];
        }
        self.adjacent.clear();
        self.adjacent.resize(edges.len() * 2, (0, 0.0));
        let mut fill = self.adjacent_start.clone();
        for e in edges {
            for (from, to) in [(e.a, e.b), (e.b, e.a)] {
                self.adjacent[fill[from as usize] as usize] = (to, e.rest_length);
                fill[from as usize] += 1;
            }
        }
    }

    /// Append to `near` the particles within `reach` of `p` along the edges, by the
    /// shortest path (a tree's branches and a loop's two ways round included).
    fn walk(&mut self, p: u32, reach: f64) {
        self.reached.clear();
        self.stack.clear();
        self.stack.push((p, 0.0));
        while let Some((i, distance)) = self.stack.pop() {
            let range = self.adjacent_start[i as usize] as usize
                ..self.adjacent_start[i as usize + 1] as usize;
            for &(j, length) in &self.adjacent[range] {
                let d = distance + length;
                if j == p || d > reach {
                    continue;
                }
                match self.reached.iter_mut().find(|r| r.0 == j) {
                    Some(r) if r.1 <= d => continue,
                    Some(r) => r.1 = d,
                    None => self.reached.push((j, d)),
                }
                self.stack.push((j, d));
            }
        }
        let start = self.near.len();
        self.near.extend(self.reached.iter().map(|r| r.0));
        self.near[start..].sort_unstable();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(lengths: &[f64]) -> Vec<Edge> {
        lengths
            .iter()
            .enumerate()
            .map(|(i, &l)| Edge::new(i as u32, i as u32 + 1, l))
            .collect()
    }

    #[test]
    fn edges_longer_than_the_reach_exempt_nothing() {
        let edges = chain(&[0.004 * REACH * 1.001; 6]);
        let mut exempt = Exempt::default();
        exempt.build(&edges, 7, 0.004);
        assert!(edges.iter().all(|e| (0..7).all(|p| !exempt.exempt(p, e))));
    }

    #[test]
    fn a_point_is_exempt_from_the_edges_it_reaches_within_a_thickness() {
        // Edges one thickness long, one rounded short, one a little long: a point
        // reaches its neighbours, so it is exempt from their edges and meets the edges
        // beyond.
        let t = 0.004;
        let edges = chain(&[t, t * (1.0 - 1e-15), t * 1.2, t, t]);
        let mut exempt = Exempt::default();
        exempt.build(&edges, 6, t);
        let exempt_from = |p: u32| -> Vec<usize> {
            (0..edges.len())
                .filter(|&k| exempt.exempt(p, &edges[k]))
                .collect()
        };
        assert_eq!(exempt_from(0), vec![0, 1]);
        assert_eq!(exempt_from(2), vec![0, 1, 2, 3]);
        assert_eq!(exempt_from(5), vec![3, 4]);
        // Half-thickness edges reach two particles each way.
        let edges = chain(&[t / 2.0; 6]);
        exempt.build(&edges, 7, t);
        assert!(exempt.exempt(0, &edges[2]) && !exempt.exempt(0, &edges[3]));
        assert!(exempt.exempt(3, &edges[0]) && exempt.exempt(3, &edges[5]));
    }

    #[test]
    fn an_update_rebuilds_for_a_new_topology_or_thickness_only() {
        let (t, short, long) = (0.004, chain(&[0.004; 3]), chain(&[0.01; 3]));
        let mut exempt = Exempt::default();
        exempt.update(1, &short, 4, t);
        assert!(exempt.exempt(0, &short[1]));
        // The same version: what was built stands.
        exempt.update(1, &long, 4, t);
        assert!(exempt.exempt(0, &short[1]));
        exempt.update(2, &long, 4, t);
        assert!(exempt.is_empty());
        exempt.update(2, &long, 4, 0.009);
        assert!(exempt.exempt(0, &long[1]));
    }

    #[test]
    fn a_loop_is_walked_both_ways_round() {
        // A triangle loop of short edges with a long tail: every corner reaches the
        // other two; the tail's far end reaches nothing.
        let t = 0.004;
        let mut edges = chain(&[t, t]);
        edges.push(Edge::new(2, 0, t));
        edges.push(Edge::new(2, 3, 0.01));
        let mut exempt = Exempt::default();
        exempt.build(&edges, 4, t);
        assert!(exempt.exempt(0, &edges[1]));
        assert!(exempt.exempt(1, &edges[2]));
        assert!(!exempt.exempt(3, &edges[0]));
        assert!(exempt.exempt(0, &edges[3]), "its end 2 is a thickness away");
    }
}
