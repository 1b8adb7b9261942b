//! Criterion benchmark of one Collide stage on settling piles of 1k, 10k and 100k
//! particles, uniform-grid broad phase against brute force.
//!
//! The pile: strands of 100 particles lying in rows 0.9 thicknesses apart, sinking at
//! a few centimetres per second with some jitter, so that every particle is in
//! proximity contact with the row below and the contact re-projection has every
//! island to solve. Each iteration restores the same velocities and
//! runs the whole stage (proximity, detection, impulses, contact re-projection).
//! Also the end-of-step crossing check alone on the `scale` layout (100 000 edges).
//! Run with `cargo bench --bench collisions`; results per machine are in
//! `benches/RESULTS.md`.

use std::hint::black_box;
use std::time::{Duration, Instant};

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::collision::broad_phase::{BroadPhase, BroadPhaseMethod};
use bevy_strands::collision::crossings::{Among, count_crossings};
use bevy_strands::model::Edge;
use bevy_strands::prelude::*;
use bevy_strands_app::fixtures::{run_collide_stage, spawn_container};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

const PER_STRAND: usize = 100;

fn pile(particles: usize, method: BroadPhaseMethod) -> (App, Vec<DVec2>) {
    let mut app = App::new();
    app.add_plugins(StrandsPlugin::manual());
    app.finish();
    app.cleanup();
    let world = app.world_mut();
    world.resource_mut::<StrandsConfig>().substeps = 1;
    let strands = particles / PER_STRAND;
    let gap = 0.9 * 0.004;
    spawn_container(
        world,
        DVec2::ZERO,
        DVec2::new(1.02, gap * (strands + 2) as f64),
    );
    for s in 0..strands {
        let points = (0..PER_STRAND).map(|i| {
            let wave = 0.001 * ((i + s) as f64 * 0.7).sin();
            DVec2::new(0.01 + 0.01 * i as f64, gap * (s + 1) as f64 + wave)
        });
        StrandBuilder::polyline(points).spawn_in(world).unwrap();
    }
    // Build topology and islands without moving anything.
    world.resource_mut::<CollisionConfig>().enabled = false;
    world.resource_mut::<StrandsConfig>().gravity = DVec2::ZERO;
    world.run_schedule(StrandsTick);
    let mut config = world.resource_mut::<CollisionConfig>();
    config.enabled = true;
    config.broad_phase = method;
    let state = world.resource::<ParticleState>();
    let velocity = (0..state.len())
        .map(|i| {
            if state.is_pinned(i) {
                DVec2::ZERO
            } else {
                let jitter = ((i * 7919) % 101) as f64 / 101.0 - 0.5;
                DVec2::new(0.02 * jitter, -0.05 - 0.03 * jitter)
            }
        })
        .collect();
    (app, velocity)
}

fn collide_stage(c: &mut Criterion) {
    let mut group = c.benchmark_group("collide_stage");
    group.sample_size(10).warm_up_time(Duration::from_secs(1));
    for particles in [1_000usize, 10_000, 100_000] {
        for method in [BroadPhaseMethod::Grid, BroadPhaseMethod::BruteForce] {
            if method == BroadPhaseMethod::BruteForce && particles > 10_000 {
                // 10¹⁰ box tests per detection pass: minutes per sample.
                continue;
            }
            let threads: &[usize] = match method {
                BroadPhaseMethod::Grid => &[1, 2],
                BroadPhaseMethod::BruteForce => &[1],
            };
            for &threads in threads {
                let (mut app, velocity) = pile(particles, method);
                let world = app.world_mut();
                world.resource_mut::<StrandsConfig>().threads = threads;
                world
                    .resource_mut::<ParticleState>()
                    .velocity
                    .copy_from_slice(&velocity);
                run_collide_stage(world);
                let impulses = world.resource::<StrandMetrics>().collisions_last_step;
                eprintln!("{particles} particles, {method:?}: {impulses} impulses per stage");
                group.throughput(Throughput::Elements(particles as u64));
                let name = format!("{}/{threads}t", format!("{method:?}").to_lowercase());
                group.bench_function(BenchmarkId::new(name, particles), |b| {
                    b.iter_custom(|iters| {
                        let mut total = Duration::ZERO;
                        for _ in 0..iters {
                            let world = app.world_mut();
                            world
                                .resource_mut::<ParticleState>()
                                .velocity
                                .copy_from_slice(&velocity);
                            let start = Instant::now();
                            run_collide_stage(world);
                            black_box(&world.resource::<ParticleState>().velocity);
                            total += start.elapsed();
                        }
                        total
                    })
                });
            }
        }
    }
    group.finish();
}

/// The `scale` scene's layout at rest: rows of wavy strands of 100 particles 1 cm
/// apart, rows 4 cm apart, strands 5 cm apart along a row.
fn scale_layout(strands: usize) -> (Vec<Edge>, Vec<DVec2>) {
    let (spacing, columns) = (0.01, (strands as f64 / 8.0).sqrt().ceil() as usize);
    let pitch = DVec2::new((PER_STRAND + 4) as f64 * spacing, 4.0 * spacing);
    let (mut edges, mut position) = (Vec::new(), Vec::new());
    for s in 0..strands {
        let (row, column) = (s / columns, s % columns);
        let start = DVec2::new(column as f64 * pitch.x, row as f64 * pitch.y);
        for i in 0..PER_STRAND {
            let wave = 0.5 * spacing * ((i + 3 * s) as f64 * 0.4).sin();
            if i > 0 {
                let a = position.len() as u32 - 1;
                edges.push(Edge::new(a, a + 1, spacing));
            }
            position.push(start + DVec2::new(i as f64 * spacing, wave));
        }
    }
    (edges, position)
}

/// The crossing check alone on the `scale` layout: counting on the collision stage's
/// grid, and building its own.
fn crossing_check(c: &mut Criterion) {
    let mut group = c.benchmark_group("crossing_check");
    group.sample_size(20).warm_up_time(Duration::from_secs(1));
    let (edges, position) = scale_layout(1000);
    let (mut broad, mut pairs) = (BroadPhase::default(), Vec::new());
    group.throughput(Throughput::Elements(edges.len() as u64));
    // The collision stage's grid after a step of free fall at 1 m/s (3.3 mm at
    // 1/300 s), boxes swept over it and inflated by the 4 mm thickness: the check
    // counts on it, as in a run, instead of building its own.
    let displacement = vec![DVec2::new(0.0, -1.0 / 300.0); position.len()];
    let end: Vec<DVec2> = (position.iter().zip(&displacement))
        .map(|(&x, &d)| x + d)
        .collect();
    let mut stage_grid = BroadPhase::default();
    stage_grid.build(&edges, &position, Some(&displacement), 0.004, 1);
    let cases = [
        ("scale_on_stage_grid", &end, true),
        ("scale", &position, false),
    ];
    for (name, at, on_stage_grid) in cases {
        for threads in [1usize, 2] {
            let id = BenchmarkId::new(format!("{name}/{threads}t"), edges.len());
            group.bench_function(id, |b| {
                b.iter(|| {
                    let found = count_crossings(
                        &edges,
                        at,
                        &mut broad,
                        on_stage_grid.then_some(&mut stage_grid),
                        Among::All,
                        BroadPhaseMethod::Grid,
                        threads,
                        &mut pairs,
                    );
                    assert_eq!(found.pairs, 0);
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, collide_stage, crossing_check);
criterion_main!(benches);
