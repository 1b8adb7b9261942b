//! The chains both rigid-body engines are given, and what is measured on them: link
//! stretch and links that cross. Pure geometry, no engine types.

use bevy_strands_app::scenario::ScaleSpec;

/// A chain of straight links laid along a strand's particles: link `k` of strand `s`
/// runs from particle `k` to particle `k + 1`.
#[derive(Clone, Debug)]
pub struct Chains {
    /// Each strand's particle positions at the start.
    pub strands: Vec<Vec<[f32; 2]>>,
    /// The box the chains fall into: (min, max).
    pub container: ([f32; 2], [f32; 2]),
    /// Half the strands' thickness: the capsule radius.
    pub radius: f32,
    pub friction: f32,
    /// Each link's mass: a strand's mass shared evenly among its links.
    pub link_mass: f32,
}

impl Chains {
    /// The built-in `pile`'s strands as chains, particle for particle where the
    /// scenario places them (its gentle wave included).
    pub fn from_scale(scale: &ScaleSpec, thickness: f64, friction: f64, mass: f64) -> Self {
        let strands = (0..scale.strands)
            .map(|s| {
                let start = scale.start(s);
                (0..scale.particles)
                    .map(|i| {
                        let wave = scale.wave() * ((i + 3 * s) as f64 * 0.4).sin();
                        [
                            (start.x + scale.spacing * i as f64) as f32,
                            (start.y + wave) as f32,
                        ]
                    })
                    .collect()
            })
            .collect();
        let container = scale.container();
        Chains {
            strands,
            container: (
                [container.min[0] as f32, container.min[1] as f32],
                [container.max[0] as f32, container.max[1] as f32],
            ),
            radius: (0.5 * thickness) as f32,
            friction: friction as f32,
            link_mass: (mass * scale.particles as f64 / (scale.particles - 1) as f64) as f32,
        }
    }

    /// Links in all chains.
    pub fn links(&self) -> usize {
        self.strands.iter().map(|s| s.len() - 1).sum()
    }

    /// Link ends, counted as particles are.
    pub fn particles(&self) -> usize {
        self.strands.iter().map(Vec::len).sum()
    }
}

/// A link as the engine left it: its two end points (the link's own, from its body's
/// pose) in chain order.
pub type Segment = [[f32; 2]; 2];

/// What one step end shows: the largest joint gap over the link length, and how many
/// pairs of links that are not neighbours in a chain cross.
pub struct StepMeasure {
    pub stretch: f32,
    pub crossed_pairs: usize,
}

/// Measure one step end. `links[s]` are strand `s`'s links in order. Two links cross
/// when their centre lines properly intersect; neighbours in one chain share an end
/// and are skipped. A uniform grid of cells one link long finds the candidate pairs.
pub fn measure(links: &[Vec<Segment>], rest: &[Vec<f32>], grid: &mut Grid) -> StepMeasure {
    let mut stretch = 0.0f32;
    for (chain, lengths) in links.iter().zip(rest) {
        for (pair, &length) in chain.windows(2).zip(lengths) {
            let gap = distance(pair[0][1], pair[1][0]);
            stretch = stretch.max(gap / length);
        }
    }
    StepMeasure {
        stretch,
        crossed_pairs: grid.crossing_pairs(links),
    }
}

fn distance(a: [f32; 2], b: [f32; 2]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// Whether segments `p` and `q` properly intersect (touching ends do not count).
pub fn segments_cross(p: Segment, q: Segment) -> bool {
    let orient = |a: [f32; 2], b: [f32; 2], c: [f32; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let (d1, d2) = (orient(q[0], q[1], p[0]), orient(q[0], q[1], p[1]));
    let (d3, d4) = (orient(p[0], p[1], q[0]), orient(p[0], p[1], q[1]));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// A reusable uniform grid over link bounding boxes.
pub struct Grid {
    cell: f32,
    cells: std::collections::HashMap<(i32, i32), Vec<(u32, u32)>>,
}

impl Grid {
    pub fn new(cell: f32) -> Self {
        Grid {
            cell,
            cells: Default::default(),
        }
    }

    /// Pairs of links that cross, each pair once (a pair in several cells is counted
    /// in the cell of its lower bounding-box corner only).
    fn crossing_pairs(&mut self, links: &[Vec<Segment>]) -> usize {
        for v in self.cells.values_mut() {
            v.clear();
        }
        let key =
            |x: f32, y: f32, cell: f32| ((x / cell).floor() as i32, (y / cell).floor() as i32);
        for (s, chain) in links.iter().enumerate() {
            for (k, seg) in chain.iter().enumerate() {
                let lo = key(
                    seg[0][0].min(seg[1][0]),
                    seg[0][1].min(seg[1][1]),
                    self.cell,
                );
                let hi = key(
                    seg[0][0].max(seg[1][0]),
                    seg[0][1].max(seg[1][1]),
                    self.cell,
                );
                for x in lo.0..=hi.0 {
                    for y in lo.1..=hi.1 {
                        self.cells
                            .entry((x, y))
                            .or_default()
                            .push((s as u32, k as u32));
                    }
                }
            }
        }
        let cell = self.cell;
        let corner = |seg: &Segment| key(seg[0][0].min(seg[1][0]), seg[0][1].min(seg[1][1]), cell);
        let mut pairs = 0;
        for (&here, members) in &self.cells {
            for (i, &(s, k)) in members.iter().enumerate() {
                for &(t, l) in &members[i + 1..] {
                    let (p, q) = (links[s as usize][k as usize], links[t as usize][l as usize]);
                    let neighbours = s == t && k.abs_diff(l) <= 1;
                    if neighbours || !segments_cross(p, q) {
                        continue;
                    }
                    // Counted where both boxes overlap first: the larger lower corner.
                    let (a, b) = (corner(&p), corner(&q));
                    if here == (a.0.max(b.0), a.1.max(b.1)) {
                        pairs += 1;
                    }
                }
            }
        }
        pairs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_segments_are_found_and_touching_or_apart_ones_are_not() {
        assert!(segments_cross(
            [[0.0, 0.0], [1.0, 1.0]],
            [[0.0, 1.0], [1.0, 0.0]]
        ));
        assert!(!segments_cross(
            [[0.0, 0.0], [1.0, 0.0]],
            [[1.0, 0.0], [2.0, 1.0]]
        ));
        assert!(!segments_cross(
            [[0.0, 0.0], [1.0, 0.0]],
            [[0.0, 0.1], [1.0, 0.1]]
        ));
    }

    #[test]
    fn the_grid_finds_a_crossing_between_chains_but_not_between_neighbours() {
        let mut grid = Grid::new(0.5);
        let a = vec![[[0.0, 0.0], [1.0, 0.0]], [[1.0, 0.0], [1.0, 1.0]]];
        let b = vec![[[0.5, -0.5], [0.5, 0.5]]];
        assert_eq!(grid.crossing_pairs(&[a.clone(), b]), 1);
        let c = vec![[[3.0, 3.0], [4.0, 3.0]]];
        assert_eq!(grid.crossing_pairs(&[a, c]), 0);
    }
}
