//! Criterion benchmarks of the constraint solve: the Thomas kernel per unknown, one
//! Constrain stage (every island projected once) on 1000 strands of 100 particles (the
//! kernel in a loop, and the plugin's islands on one and two threads), and
//! one projection of a tree and of a graph of about 2000 edges (sparse LDLᵀ) beside a
//! chain of as many edges.
//!
//! Run with `cargo bench --bench constraints`; results per machine are recorded in
//! `benches/RESULTS.md`.

use std::hint::black_box;
use std::time::{Duration, Instant};

use bevy::math::DVec2;
use bevy_strands::constraints::Islands;
use bevy_strands::constraints::graph::GraphLayout;
use bevy_strands::constraints::island_edge::IslandEdge;
use bevy_strands::constraints::islands::find_islands;
use bevy_strands::constraints::projection::{
    Bodies, Chain, Graph, IslandScratch, IslandView, project_chain, project_island,
};
use bevy_strands::linalg::tridiagonal::solve_tridiagonal;
use bevy_strands::metrics::IterationStats;
use bevy_strands::model::Edge;
use bevy_strands::prelude::*;
use criterion::{Bencher, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// A strand-shaped SPD system: `4|e|²(w_a + w_b)` on the diagonal, `−4 w e·e'` beside.
fn strand_system(n: usize, rng: &mut StdRng) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let edges: Vec<DVec2> = (0..n)
        .map(|_| 0.01 * DVec2::from_angle(rng.random_range(0.0..std::f64::consts::TAU)))
        .collect();
    let diagonal = edges.iter().map(|e| 8.0 * e.length_squared()).collect();
    let mut lower = vec![0.0; n];
    let mut upper = vec![0.0; n];
    for k in 0..n.saturating_sub(1) {
        upper[k] = -4.0 * edges[k].dot(edges[k + 1]);
        lower[k + 1] = upper[k];
    }
    let rhs = (0..n).map(|_| rng.random_range(-1e-6..1e-6)).collect();
    (lower, diagonal, upper, rhs)
}

fn thomas(c: &mut Criterion) {
    let mut group = c.benchmark_group("thomas_solve");
    let mut rng = StdRng::seed_from_u64(1);
    for n in [10usize, 100, 1000, 100_000] {
        let (lower, diagonal, upper, rhs) = strand_system(n, &mut rng);
        let mut scratch = vec![0.0; n];
        group.throughput(Throughput::Elements(n as u64));
        // The right-hand side is copied into the same buffer each time, as the
        // projection builds it just before solving: warm in cache. (Fresh clones made
        // ahead by the harness were cold: at 1 000 unknowns a third of the time went to
        // loading them.) The copy is in the time.
        let mut x = rhs.clone();
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                x.copy_from_slice(&rhs);
                solve_tridiagonal(&lower, &diagonal, &upper, black_box(&mut x), &mut scratch)
            })
        });
    }
    group.finish();
}

/// `strands` wiggly strands of `particles`, with velocities a falling, swinging pile
/// would have: gravity's kick on top of motion along and across the strand.
struct Pile {
    position: Vec<DVec2>,
    velocity: Vec<DVec2>,
    inverse_mass: Vec<f64>,
    edges: Vec<IslandEdge>,
    chains: Vec<std::ops::Range<usize>>,
}

fn pile(strands: usize, particles: usize, rng: &mut StdRng) -> Pile {
    let spacing = 0.01;
    let mut pile = Pile {
        position: Vec::new(),
        velocity: Vec::new(),
        inverse_mass: Vec::new(),
        edges: Vec::new(),
        chains: Vec::new(),
    };
    for s in 0..strands {
        let first = pile.position.len() as u32;
        let mut x = DVec2::new((s % 40) as f64, (s / 40) as f64);
        let mut heading: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let start = pile.edges.len();
        for i in 0..particles {
            if i > 0 {
                heading += rng.random_range(-0.3..0.3);
                x += spacing * DVec2::from_angle(heading);
                let (a, b) = (first + i as u32 - 1, first + i as u32);
                pile.edges.push(IslandEdge {
                    a,
                    b,
                    rest_length: spacing,
                    edge: pile.edges.len() as u32,
                });
            }
            pile.position.push(x);
            pile.velocity.push(DVec2::new(
                rng.random_range(-0.5..0.5),
                rng.random_range(-0.5..0.5),
            ));
            pile.inverse_mass.push(1.0);
        }
        pile.chains.push(start..pile.edges.len());
    }
    pile
}

/// Time `stage` on velocities reset to `initial` before each run (the reset untimed).
fn bench_from(b: &mut Bencher, initial: &[DVec2], mut stage: impl FnMut(&mut [DVec2])) {
    let mut velocity = initial.to_vec();
    b.iter_custom(|iters| {
        let mut total = Duration::ZERO;
        for _ in 0..iters {
            velocity.copy_from_slice(initial);
            let start = Instant::now();
            stage(&mut velocity);
            total += start.elapsed();
        }
        black_box(&velocity);
        total
    })
}

fn constraint_stage(c: &mut Criterion) {
    let mut group = c.benchmark_group("constraint_stage");
    let mut rng = StdRng::seed_from_u64(2);
    let (strands, particles) = (1000, 100);
    let pile = pile(strands, particles, &mut rng);
    // The plugin's defaults: tolerance 1e-12, at most 20 iterations, end-of-step.
    let settings = ConstraintConfig::default().projection();
    let mut scratch = IslandScratch::default();
    scratch.reserve(particles, particles + 1);
    let dt = 1.0 / 3000.0;
    group.throughput(Throughput::Elements((strands * particles) as u64));
    group.bench_function(BenchmarkId::new("1000x100", "end_of_step"), |b| {
        bench_from(b, &pile.velocity, |velocity| {
            for range in &pile.chains {
                let chain = Chain {
                    edges: &pile.edges[range.clone()],
                    closed: false,
                };
                let bodies = Bodies::new(&pile.position, velocity, &pile.inverse_mass);
                black_box(project_chain(chain, bodies, dt, &settings, &mut scratch));
            }
        })
    });
    // The same stage through the plugin's islands, on one thread and on two.
    let model_edges: Vec<Edge> = (pile.edges.iter())
        .map(|e| Edge::new(e.a, e.b, e.rest_length))
        .collect();
    let mut islands = Islands::default();
    islands.set = find_islands(&model_edges, &vec![false; pile.position.len()]);
    islands.solved = (0..islands.set.islands.len()).collect();
    let mut stats = IterationStats::default();
    for threads in [1, 2] {
        group.bench_function(BenchmarkId::new("1000x100/islands", threads), |b| {
            bench_from(b, &pile.velocity, |velocity| {
                let mut bodies = Bodies::new(&pile.position, velocity, &pile.inverse_mass);
                islands.project(&mut bodies, dt, &settings, &mut stats, threads);
            })
        });
    }
    group.finish();
}

/// Particles and edges (rest lengths from the positions) of a structure.
struct Structure {
    position: Vec<DVec2>,
    edges: Vec<IslandEdge>,
}

impl Structure {
    fn new(position: Vec<DVec2>, pairs: &[(u32, u32)]) -> Structure {
        let edges = IslandEdge::between(&position, pairs);
        Structure { position, edges }
    }
}

/// A chain of 1999 edges; a comb (a spine of 1000 edges with a tooth of 10 edges at
/// every tenth particle: 1999 edges, a tree); a ladder (two rails of 1000 particles
/// and 100 rungs: 2098 edges, a graph of 99 loops).
fn structures() -> Vec<(&'static str, Structure)> {
    let spacing = 0.01;
    let chain = Structure::new(
        (0..2000)
            .map(|i| DVec2::new(spacing * i as f64, 0.0))
            .collect(),
        &(0..1999).map(|i| (i, i + 1)).collect::<Vec<_>>(),
    );
    let mut comb_points: Vec<DVec2> = (0..1001)
        .map(|i| DVec2::new(spacing * i as f64, 0.0))
        .collect();
    let mut comb_pairs: Vec<(u32, u32)> = (0..1000).map(|i| (i, i + 1)).collect();
    for root in (0..1000).step_by(10) {
        let mut previous = root as u32;
        for j in 1..=10 {
            comb_points.push(DVec2::new(spacing * root as f64, -spacing * j as f64));
            let next = comb_points.len() as u32 - 1;
            comb_pairs.push((previous, next));
            previous = next;
        }
    }
    let comb = Structure::new(comb_points, &comb_pairs);
    let mut ladder_points: Vec<DVec2> = (0..1000)
        .map(|i| DVec2::new(spacing * i as f64, 0.0))
        .collect();
    ladder_points.extend((0..1000).map(|i| DVec2::new(spacing * i as f64, 0.02)));
    let mut ladder_pairs: Vec<(u32, u32)> = (0..999).map(|i| (i, i + 1)).collect();
    ladder_pairs.extend((1000..1999).map(|i| (i, i + 1)));
    ladder_pairs.extend((0..1000).step_by(10).map(|i| (i, i + 1000)));
    let ladder = Structure::new(ladder_points, &ladder_pairs);
    vec![("chain", chain), ("tree", comb), ("graph", ladder)]
}

fn structure_projection(c: &mut Criterion) {
    let mut group = c.benchmark_group("projection_by_kind");
    let mut rng = StdRng::seed_from_u64(3);
    // The plugin's defaults: tolerance 1e-12, at most 20 iterations, end-of-step.
    let settings = ConstraintConfig::default().projection();
    let dt = 1.0 / 3000.0;
    for (name, mut structure) in structures() {
        let n = structure.position.len();
        let layout =
            (name != "chain").then(|| GraphLayout::new(&mut structure.edges, &vec![false; n]));
        let initial: Vec<DVec2> = (0..n)
            .map(|_| DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
            .collect();
        let inverse_mass = vec![1.0; n];
        let mut velocity = initial.clone();
        let mut scratch = IslandScratch::default();
        group.throughput(Throughput::Elements(structure.edges.len() as u64));
        group.bench_function(BenchmarkId::new(name, structure.edges.len()), |b| {
            b.iter(|| {
                velocity.copy_from_slice(&initial);
                let island = match &layout {
                    Some(layout) => IslandView::Graph(Graph {
                        edges: &structure.edges,
                        layout,
                    }),
                    None => IslandView::Chain(Chain {
                        edges: &structure.edges,
                        closed: false,
                    }),
                };
                let bodies = Bodies::new(&structure.position, &mut velocity, &inverse_mass);
                black_box(project_island(island, bodies, dt, &settings, &mut scratch))
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(Duration::from_secs(4));
    targets = thomas, constraint_stage, structure_projection
}
criterion_main!(benches);
