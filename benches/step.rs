//! Criterion benchmark of a step's fixed cost on small scenes: one step of 1/300 s (a
//! tick of one step) of the built-in `long_strand` (60 particles) lying on the floor,
//! of a 10-particle strand lying on the floor (the `scale` scene with one strand), and
//! of the same strand in free fall with collisions off, on one thread with sleeping
//! off, so that every stage runs. What each stage takes of such a step is printed by
//! `strands run long_strand --profile`. Run with `cargo bench --bench step`; results
//! per machine are in `benches/RESULTS.md`.

use std::time::Duration;

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::fixtures::{tick, ticks};
use bevy_strands_app::runner::{RunOptions, headless_app, load_scenario};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

/// A headless app of `options`' scene, one step of 1/300 s a tick, one thread, awake,
/// run for `settle` ticks first.
fn app_after(options: RunOptions, settle: usize) -> App {
    let mut scenario = load_scenario(&RunOptions {
        no_sleep: true,
        dt: Some(1.0 / 300.0),
        substeps: Some(1),
        threads: Some(1),
        ..options
    })
    .expect("the scene loads");
    scenario.step.sleep.enabled = false;
    let mut app = headless_app(&scenario).expect("the scene spawns");
    ticks(&mut app, settle);
    app
}

fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let scenes = [
        (
            "long_strand_resting",
            RunOptions {
                scenario: "long_strand".into(),
                ..Default::default()
            },
            600,
        ),
        (
            "strand_10_resting",
            RunOptions {
                scenario: "scale".into(),
                strands: Some(1),
                particles: Some(10),
                ..Default::default()
            },
            600,
        ),
        (
            "strand_10_free_no_collisions",
            RunOptions {
                scenario: "scale".into(),
                strands: Some(1),
                particles: Some(10),
                no_collisions: true,
                ..Default::default()
            },
            0,
        ),
    ];
    for (name, options, settle) in scenes {
        let mut app = app_after(options, settle);
        let particles = app.world().resource::<ParticleState>().len();
        let metrics = app.world().resource::<StrandMetrics>();
        assert_eq!(metrics.asleep_particles, 0, "{name}: awake");
        assert!(metrics.max_rel_length_error < 1e-12, "{name}: exact");
        group.throughput(Throughput::Elements(particles as u64));
        group.bench_function(BenchmarkId::new(name, "1t"), |b| b.iter(|| tick(&mut app)));
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
