//! Criterion benchmark of a settled pile asleep and awake: the built-in pile (200
//! strands of 15 particles, 3 000 particles) run until every strand sleeps, a tick
//! (three steps of 1/300 s) timed asleep, then the same pile woken (sleeping switched
//! off: the same positions, at rest) and a tick timed awake, on one and two threads.
//! Asleep, a tick should cost a few per cent of an awake one. Run with
//! `cargo bench --bench sleeping`; results per machine are in `benches/RESULTS.md`.

use std::time::Duration;

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::fixtures::tick;
use bevy_strands_app::runner::{RunOptions, headless_app, load_scenario};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

fn pile_tick(c: &mut Criterion) {
    let scenario = load_scenario(&RunOptions {
        scenario: "pile".into(),
        ..Default::default()
    })
    .expect("the pile loads");
    let mut app = headless_app(&scenario).expect("the pile spawns");
    let particles = app.world().resource::<ParticleState>().len();
    // Twenty simulated seconds at most: the pile lands, settles and sleeps.
    for _ in 0..2000 {
        tick(&mut app);
        let metrics = app.world().resource::<StrandMetrics>();
        if metrics.asleep_particles == metrics.particles - 4 {
            break;
        }
    }
    let metrics = app.world().resource::<StrandMetrics>();
    assert_eq!(
        metrics.asleep_particles,
        metrics.particles - 4,
        "the whole pile sleeps (the box's four corners are walls)"
    );

    let mut group = c.benchmark_group("pile_tick");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    group.throughput(Throughput::Elements(particles as u64 * 3));
    for threads in [1usize, 2] {
        app.world_mut().resource_mut::<StrandsConfig>().threads = threads;
        let id = BenchmarkId::new("asleep", format!("{threads}t"));
        group.bench_function(id, |b| b.iter(|| tick(&mut app)));
    }
    app.world_mut()
        .resource_mut::<StrandsConfig>()
        .sleep
        .enabled = false;
    tick(&mut app);
    assert_eq!(app.world().resource::<StrandMetrics>().asleep_particles, 0);
    for threads in [1usize, 2] {
        app.world_mut().resource_mut::<StrandsConfig>().threads = threads;
        let id = BenchmarkId::new("awake", format!("{threads}t"));
        group.bench_function(id, |b| b.iter(|| tick(&mut app)));
    }
    group.finish();
}

criterion_group!(benches, pile_tick);
criterion_main!(benches);
