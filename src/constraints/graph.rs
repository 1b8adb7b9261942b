//! The layout of a tree or graph island, built once per topology change: its particles
//! in local numbering, each edge's ends, the edges at each particle, and the sparse
//! plan of its system `J W Jᵀ`.
//!
//! The island's edges are put in the plan's elimination order, so that edge k is
//! unknown k of the factor and the projection needs no permutation.

use super::island_edge::IslandEdge;
use crate::linalg::sparse::SparsePlan;

/// An off-diagonal entry of `J W Jᵀ`: edges k and l meet at a free particle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coupling {
    /// Where the entry sits among the factor's values.
    pub value: u32,
    /// The two edges.
    pub k: u32,
    /// The two edges.
    pub l: u32,
    /// The shared particle (local).
    pub particle: u32,
    /// +1 if the particle is the same end (start or end) of both edges, −1 otherwise.
    pub sign: f64,
}

/// A tree or graph island as the projection sees it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GraphLayout {
    /// Packed index of each local particle.
    pub particles: Vec<u32>,
    /// Local ends (start, end) of each edge, in the island's (elimination) order.
    pub ends: Vec<(u32, u32)>,
    incidence_start: Vec<u32>,
    /// Edges at each local particle, with −1 where the particle is the start, +1 the end.
    incidence: Vec<(u32, f64)>,
    /// The off-diagonal entries of the system.
    pub couplings: Vec<Coupling>,
    /// The most edges meeting at one particle.
    pub max_degree: usize,
    /// The system's elimination order and fill.
    pub plan: SparsePlan,
}

impl GraphLayout {
    /// Lay out the island of `edges` (packed particle indices), reordering the edges
    /// into elimination order. Pinned particles couple nothing (their inverse mass is 0).
    pub fn new(edges: &mut [IslandEdge], pinned: &[bool]) -> GraphLayout {
        let mut particles: Vec<u32> = edges.iter().flat_map(|e| [e.a, e.b]).collect();
        particles.sort_unstable();
        particles.dedup();
        let local = |p: u32| particles.binary_search(&p).expect("an end of the island") as u32;
        // Pairs of edges meeting at a free particle, in the caller's order.
        let mut at_particle: Vec<(u32, u32)> = edges
            .iter()
            .enumerate()
            .flat_map(|(k, e)| [(local(e.a), k as u32), (local(e.b), k as u32)])
            .filter(|&(j, _)| !pinned[particles[j as usize] as usize])
            .collect();
        at_particle.sort_unstable();
        let mut pairs = Vec::new();
        for group in at_particle.chunk_by(|x, y| x.0 == y.0) {
            for (i, &(_, k)) in group.iter().enumerate() {
                pairs.extend(group[i + 1..].iter().map(|&(_, l)| (k, l)));
            }
        }
        let plan = SparsePlan::new(edges.len(), &pairs);
        let reordered: Vec<IslandEdge> = plan.order.iter().map(|&k| edges[k as usize]).collect();
        edges.copy_from_slice(&reordered);

        let ends: Vec<(u32, u32)> = edges.iter().map(|e| (local(e.a), local(e.b))).collect();
        let mut incidence: Vec<(u32, u32, f64)> = ends
            .iter()
            .enumerate()
            .flat_map(|(k, &(a, b))| [(a, k as u32, -1.0), (b, k as u32, 1.0)])
            .collect();
        incidence.sort_unstable_by_key(|&(j, k, _)| (j, k));
        let mut incidence_start = vec![0u32; particles.len() + 1];
        for &(j, _, _) in &incidence {
            incidence_start[j as usize + 1] += 1;
        }
        for j in 0..particles.len() {
            incidence_start[j + 1] += incidence_start[j];
        }
        let mut couplings = Vec::new();
        for group in incidence.chunk_by(|x, y| x.0 == y.0) {
            let j = group[0].0;
            if pinned[particles[j as usize] as usize] {
                continue;
            }
            for (i, &(_, k, sk)) in group.iter().enumerate() {
                for &(_, l, sl) in &group[i + 1..] {
                    let value = plan
                        .value_index(k as usize, l as usize)
                        .expect("every coupling is in the plan");
                    couplings.push(Coupling {
                        value: value as u32,
                        k,
                        l,
                        particle: j,
                        sign: sk * sl,
                    });
                }
            }
        }
        let max_degree = incidence_start
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize)
            .max()
            .unwrap_or(0);
        GraphLayout {
            particles,
            ends,
            max_degree,
            incidence_start,
            incidence: incidence.into_iter().map(|(_, k, s)| (k, s)).collect(),
            couplings,
            plan,
        }
    }

    /// The edges at local particle `j`, each with −1 where `j` is its start and +1
    /// where it is its end.
    pub fn incident(&self, j: usize) -> &[(u32, f64)] {
        &self.incidence[self.incidence_start[j] as usize..self.incidence_start[j + 1] as usize]
    }
}
