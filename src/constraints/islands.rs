//! Islands: the groups of constrained edges that must be solved together.
//!
//! The nodes of the constraint graph are free particles and its edges the dynamic
//! strand edges; a pinned particle has infinite mass, couples nothing, and so splits
//! islands. An island is a path, a cycle, a tree or a general graph, and that kind
//! picks its solver. Found once per topology change, never per step.

use std::ops::Range;

use super::graph::GraphLayout;
use super::island_edge::IslandEdge;
use crate::model::{Edge, UnionFind};

/// The shape of an island's constraint graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum IslandKind {
    /// A chain: an open strand, or a piece of one between pins.
    Path,
    /// A single loop of free particles.
    Cycle,
    /// Branching without loops.
    Tree,
    /// Anything else: several loops, cross-links, or two edges on the same particles.
    Graph,
}

impl IslandKind {
    /// Lower-case name for messages and reports.
    pub fn name(self) -> &'static str {
        match self {
            IslandKind::Path => "path",
            IslandKind::Cycle => "cycle",
            IslandKind::Tree => "tree",
            IslandKind::Graph => "graph",
        }
    }
}

/// One island: its kind and its edges in [`IslandSet::edges`].
///
/// For a path, edge `k + 1` starts where edge `k` ends; for a cycle, in addition, the
/// last edge ends where the first starts. Trees and graphs keep their edges in the
/// elimination order of their [`GraphLayout`].
#[derive(Clone, Debug, PartialEq)]
pub struct Island {
    /// Its shape.
    pub kind: IslandKind,
    /// Its edges.
    pub edges: Range<usize>,
    /// Whether two of its edges join the same two particles (a redundant constraint:
    /// the system is singular and no solver accepts it).
    pub duplicate_edge: bool,
    /// The layout of a tree or graph (index into [`IslandSet::graphs`]).
    pub graph: Option<usize>,
}

/// All islands of a topology.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IslandSet {
    /// The islands.
    pub islands: Vec<Island>,
    /// Their edges, island by island.
    pub edges: Vec<IslandEdge>,
    /// The layouts of the tree and graph islands.
    pub graphs: Vec<GraphLayout>,
}

/// Find and classify the islands of the dynamic edges.
pub fn find_islands(edges: &[Edge], pinned: &[bool]) -> IslandSet {
    let n = pinned.len();
    let mut roots = UnionFind::new(n);
    for e in edges.iter().filter(|e| !e.is_static) {
        if !pinned[e.a as usize] && !pinned[e.b as usize] {
            let _ = roots.union(e.a as usize, e.b as usize);
        }
    }
    // Group edges by the root of their free end (every dynamic edge has one).
    let free_end = |e: &Edge| if pinned[e.a as usize] { e.b } else { e.a } as usize;
    let mut island_of_root = vec![u32::MAX; n];
    let mut members: Vec<Vec<u32>> = Vec::new();
    for (k, e) in edges.iter().enumerate().filter(|(_, e)| !e.is_static) {
        let root = roots.find(free_end(e));
        if island_of_root[root] == u32::MAX {
            island_of_root[root] = members.len() as u32;
            members.push(Vec::new());
        }
        members[island_of_root[root] as usize].push(k as u32);
    }

    let mut set = IslandSet::default();
    let mut degree = vec![0u32; n];
    let mut chain_links = vec![[NO_EDGE; 2]; n];
    for group in &members {
        let start = set.edges.len();
        let (kind, duplicate_edge) = classify(edges, group, pinned, &mut degree);
        match kind {
            IslandKind::Path | IslandKind::Cycle => {
                for &k in group {
                    let e = &edges[k as usize];
                    for p in [e.a as usize, e.b as usize]
                        .into_iter()
                        .filter(|&p| !pinned[p])
                    {
                        let slot = usize::from(chain_links[p][0] != NO_EDGE);
                        chain_links[p][slot] = k;
                    }
                }
                order_chain(
                    edges,
                    group,
                    pinned,
                    &degree,
                    &chain_links,
                    kind,
                    &mut set.edges,
                );
                for &k in group {
                    let e = &edges[k as usize];
                    chain_links[e.a as usize] = [NO_EDGE; 2];
                    chain_links[e.b as usize] = [NO_EDGE; 2];
                }
            }
            IslandKind::Tree | IslandKind::Graph => set.edges.extend(group.iter().map(|&k| {
                let e = &edges[k as usize];
                IslandEdge {
                    a: e.a,
                    b: e.b,
                    rest_length: e.rest_length,
                    edge: k,
                }
            })),
        }
        let graph =
            (matches!(kind, IslandKind::Tree | IslandKind::Graph) && !duplicate_edge).then(|| {
                let layout = GraphLayout::new(&mut set.edges[start..], pinned);
                set.graphs.push(layout);
                set.graphs.len() - 1
            });
        for &k in group {
            let e = &edges[k as usize];
            degree[e.a as usize] = 0;
            degree[e.b as usize] = 0;
        }
        set.islands.push(Island {
            kind,
            edges: start..set.edges.len(),
            duplicate_edge,
            graph,
        });
    }
    set
}

/// Kind of the island made of `group`; leaves each free particle's degree in `degree`.
fn classify(
    edges: &[Edge],
    group: &[u32],
    pinned: &[bool],
    degree: &mut [u32],
) -> (IslandKind, bool) {
    let mut free_nodes = 0usize;
    let mut pinned_ends = 0usize;
    for &k in group {
        let e = &edges[k as usize];
        for p in [e.a as usize, e.b as usize] {
            if pinned[p] {
                pinned_ends += 1; // each pinned end is a leaf of its own
            } else {
                free_nodes += usize::from(degree[p] == 0);
                degree[p] += 1;
            }
        }
    }
    let nodes = free_nodes + pinned_ends;
    let max_degree = group
        .iter()
        .flat_map(|&k| [edges[k as usize].a, edges[k as usize].b])
        .map(|p| degree[p as usize])
        .max()
        .unwrap_or(0);
    let mut pairs: Vec<(u32, u32)> = group
        .iter()
        .map(|&k| {
            let e = &edges[k as usize];
            (e.a.min(e.b), e.a.max(e.b))
        })
        .collect();
    pairs.sort_unstable();
    let duplicate_edge = pairs.windows(2).any(|w| w[0] == w[1]);
    let kind = if duplicate_edge {
        IslandKind::Graph
    } else if group.len() + 1 == nodes {
        if max_degree <= 2 {
            IslandKind::Path
        } else {
            IslandKind::Tree
        }
    } else if group.len() == nodes && pinned_ends == 0 && max_degree == 2 {
        IslandKind::Cycle
    } else {
        IslandKind::Graph
    };
    (kind, duplicate_edge)
}

const NO_EDGE: u32 = u32::MAX;

/// Append the edges of a path or cycle in walking order, each oriented forward.
/// `links` holds the (at most two) island edges at each free particle.
fn order_chain(
    edges: &[Edge],
    group: &[u32],
    pinned: &[bool],
    degree: &[u32],
    links: &[[u32; 2]],
    kind: IslandKind,
    out: &mut Vec<IslandEdge>,
) {
    // A path starts at a pinned end or at a free particle of degree 1; a cycle anywhere.
    let (mut at, mut via) = group
        .iter()
        .find_map(|&k| {
            let e = &edges[k as usize];
            [e.a, e.b]
                .into_iter()
                .find(|&p| {
                    pinned[p as usize] || (kind == IslandKind::Path && degree[p as usize] == 1)
                })
                .map(|p| (p, k))
        })
        .unwrap_or((edges[group[0] as usize].a, group[0]));
    for _ in 0..group.len() {
        let e = &edges[via as usize];
        let next = if e.a == at { e.b } else { e.a };
        out.push(IslandEdge {
            a: at,
            b: next,
            rest_length: e.rest_length,
            edge: via,
        });
        if pinned[next as usize] {
            break;
        }
        let [first, second] = links[next as usize];
        let following = if first == via { second } else { first };
        if following == NO_EDGE {
            break;
        }
        at = next;
        via = following;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(a: u32, b: u32) -> Edge {
        Edge::new(a, b, 1.0)
    }

    fn chain_is_connected(set: &IslandSet, island: &Island) {
        let edges = &set.edges[island.edges.clone()];
        for w in edges.windows(2) {
            assert_eq!(w[0].b, w[1].a, "{edges:?}");
        }
    }

    #[test]
    fn an_open_strand_is_one_path_in_order() {
        // Edges listed out of order and against the walking direction.
        let edges = [edge(2, 3), edge(1, 0), edge(1, 2), edge(4, 3)];
        let set = find_islands(&edges, &[false; 5]);
        assert_eq!(set.islands.len(), 1);
        assert_eq!(set.islands[0].kind, IslandKind::Path);
        chain_is_connected(&set, &set.islands[0]);
        assert_eq!(set.edges.len(), 4);
    }

    #[test]
    fn an_interior_pin_splits_a_strand_into_two_paths() {
        let edges = [edge(0, 1), edge(1, 2), edge(2, 3), edge(3, 4)];
        let mut pinned = [false; 5];
        pinned[2] = true;
        let set = find_islands(&edges, &pinned);
        assert_eq!(set.islands.len(), 2);
        for island in &set.islands {
            assert_eq!(island.kind, IslandKind::Path);
            assert_eq!(island.edges.len(), 2);
            chain_is_connected(&set, island);
        }
    }

    #[test]
    fn static_edges_are_dropped_and_pinned_ends_terminate_paths() {
        let mut wall = edge(5, 6);
        wall.is_static = true;
        let edges = [edge(0, 1), edge(1, 2), wall];
        let mut pinned = [false; 7];
        pinned[0] = true;
        pinned[5] = true;
        pinned[6] = true;
        let set = find_islands(&edges, &pinned);
        assert_eq!(set.islands.len(), 1);
        let path = &set.edges[set.islands[0].edges.clone()];
        assert_eq!(path.len(), 2);
        assert!(
            path[0].a == 0 || path[1].b == 0,
            "walk starts or ends at the pin"
        );
    }

    #[test]
    fn a_loop_pinned_at_one_particle_is_a_path_from_pin_to_pin() {
        let edges = [edge(0, 1), edge(1, 2), edge(2, 3), edge(3, 0)];
        let mut pinned = [false; 4];
        pinned[0] = true;
        let set = find_islands(&edges, &pinned);
        assert_eq!(set.islands.len(), 1);
        assert_eq!(set.islands[0].kind, IslandKind::Path);
        let path = &set.edges[set.islands[0].edges.clone()];
        assert_eq!(path.len(), 4);
        assert_eq!((path[0].a, path[3].b), (0, 0));
        chain_is_connected(&set, &set.islands[0]);
    }

    #[test]
    fn loops_trees_graphs_and_duplicates_are_told_apart() {
        let cycle = [edge(0, 1), edge(1, 2), edge(2, 0)];
        let set = find_islands(&cycle, &[false; 3]);
        assert_eq!(set.islands[0].kind, IslandKind::Cycle);
        chain_is_connected(&set, &set.islands[0]);
        let edges = &set.edges;
        assert_eq!(edges[2].b, edges[0].a);

        let tree = [edge(0, 1), edge(1, 2), edge(1, 3)];
        assert_eq!(
            find_islands(&tree, &[false; 4]).islands[0].kind,
            IslandKind::Tree
        );

        let two_loops = [edge(0, 1), edge(1, 2), edge(2, 0), edge(2, 3), edge(3, 0)];
        assert_eq!(
            find_islands(&two_loops, &[false; 4]).islands[0].kind,
            IslandKind::Graph
        );

        let duplicate = [edge(0, 1), edge(1, 0)];
        let set = find_islands(&duplicate, &[false; 2]);
        assert_eq!(set.islands[0].kind, IslandKind::Graph);
        assert!(set.islands[0].duplicate_edge);

        // Two edges from one free particle to the same pin: redundant, refused.
        let mut pinned = [false; 2];
        pinned[0] = true;
        let set = find_islands(&duplicate, &pinned);
        assert!(set.islands[0].duplicate_edge);
    }

    #[test]
    fn separate_strands_are_separate_islands() {
        let edges = [edge(0, 1), edge(1, 2), edge(3, 4), edge(5, 6), edge(6, 7)];
        let set = find_islands(&edges, &[false; 8]);
        assert_eq!(set.islands.len(), 3);
        assert!(set.islands.iter().all(|i| i.kind == IslandKind::Path));
    }
}
