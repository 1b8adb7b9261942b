//! Criterion benchmark of the furry creature's ticks, one second into its run:
//! `furry_creature` (hair that stands out; a tick is one step of 1/60 s) and
//! `furry_creature_limp` (limp hair lying in a mat, one dense contact problem; three
//! steps of 1/300 s), on one and two threads. The run goes on from tick to tick, so
//! each sample is a stretch of the same motion. Run with `cargo bench --bench fur`;
//! results per machine are in `benches/RESULTS.md`.

use std::time::Duration;

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::fixtures::{tick, ticks};
use bevy_strands_app::runner::{RunOptions, headless_app, load_scenario};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

fn fur_tick(c: &mut Criterion) {
    let mut group = c.benchmark_group("fur_tick");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for scene in ["furry_creature", "furry_creature_limp"] {
        for threads in [1usize, 2] {
            let options = RunOptions {
                scenario: scene.into(),
                ..Default::default()
            };
            let scenario = load_scenario(&options).expect("a built-in scene");
            let mut app = headless_app(&scenario).expect("the scene spawns");
            app.world_mut().resource_mut::<StrandsConfig>().threads = threads;
            // One second in: the hairs have left their straight start.
            let substeps = u64::from(scenario.step.substeps);
            let tick_length = scenario.step.dt * substeps as f64;
            ticks(&mut app, (1.0 / tick_length).round() as usize);
            let particles = app.world().resource::<ParticleState>().len();
            group.throughput(Throughput::Elements(particles as u64 * substeps));
            let id = BenchmarkId::new(scene, format!("{threads}t"));
            group.bench_function(id, |b| b.iter(|| tick(&mut app)));
        }
    }
    group.finish();
}

criterion_group!(benches, fur_tick);
criterion_main!(benches);
