//! What a game's frame costs: the worlds of the `game`, `physics_world` and
//! `rapier_world` examples (`bevy_strands_app::worlds`), headless on `MinimalPlugins`,
//! each frame one 1/60 s fixed tick (the strands in 10 substeps; avian's or Rapier's
//! step too in the two bodies worlds). First
//! ten simulated seconds from the spawn are timed frame by frame — the crates drop,
//! land and settle, the lantern swings, the hair falls — and their median, 99th
//! percentile and worst printed; then criterion times a frame of the settled world. On
//! one and two threads. Run with
//! `cargo bench -p bevy_strands_app --features avian,rapier --bench frame`; results per
//! machine are in `benches/RESULTS.md`.

use std::time::{Duration, Instant};

use avian2d::prelude::*;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_strands::prelude::*;
use bevy_strands_app::worlds::game::{game_config, spawn_game_world};
use bevy_strands_app::worlds::physics_world::{
    PhysicsWorldPlugin, physics_world_config, spawn_physics_world,
};
use bevy_strands_app::worlds::rapier_world::{
    RapierWorldPlugin, rapier_world_config, spawn_rapier_world,
};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

const FRAME: f64 = 1.0 / 60.0;

/// Which example's world.
#[derive(Clone, Copy, PartialEq)]
enum World {
    Game,
    Avian,
    Rapier,
}

/// A headless app whose every update is one fixed tick of 1/60 s.
fn headless(world: World, threads: usize) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, StrandsPlugin::default()))
        .insert_resource(Time::<Fixed>::from_duration(Duration::from_secs_f64(FRAME)))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
            FRAME,
        )));
    match world {
        World::Game => {
            app.insert_resource(game_config());
        }
        World::Avian => {
            app.add_plugins((
                PhysicsPlugins::default(),
                StrandsAvianPlugin::default(),
                PhysicsWorldPlugin,
            ))
            .insert_resource(physics_world_config());
        }
        World::Rapier => {
            app.add_plugins((RapierWorldPlugin, StrandsRapierPlugin::default()))
                .insert_resource(rapier_world_config());
        }
    }
    app.world_mut().resource_mut::<StrandsConfig>().threads = threads;
    app.finish();
    app.cleanup();
    let mut commands = app.world_mut().commands();
    match world {
        World::Game => {
            spawn_game_world(&mut commands);
        }
        World::Avian => {
            spawn_physics_world(&mut commands);
        }
        World::Rapier => {
            spawn_rapier_world(&mut commands);
        }
    }
    app.world_mut().flush();
    // The first update starts the clocks; the fixed tick runs from the second.
    app.update();
    app
}

/// Time `n` frames, one by one.
fn frames(app: &mut App, n: usize) -> Vec<Duration> {
    (0..n)
        .map(|_| {
            let start = Instant::now();
            app.update();
            start.elapsed()
        })
        .collect()
}

fn frame(c: &mut Criterion) {
    let mut group = c.benchmark_group("frame");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let worlds = [
        ("game", World::Game),
        ("physics_world", World::Avian),
        ("rapier_world", World::Rapier),
    ];
    for (name, world) in worlds {
        for threads in [1usize, 2] {
            let mut app = headless(world, threads);
            let mut times = frames(&mut app, 600);
            // Where the slowest frames fall: a spike at the spawn is not one in play.
            let mut order: Vec<usize> = (0..times.len()).collect();
            order.sort_by(|&a, &b| times[b].cmp(&times[a]));
            let slowest: Vec<String> = order[..5]
                .iter()
                .map(|&k| format!("{k}: {:.2}", times[k].as_secs_f64() * 1e3))
                .collect();
            times.sort();
            let ms = |d: Duration| d.as_secs_f64() * 1e3;
            let metrics = app.world().resource::<StrandMetrics>();
            println!(
                "{name} {threads}t, the slowest frames (frame: ms): {}",
                slowest.join(", ")
            );
            println!(
                "{name} {threads}t, first 10 s (600 frames): median {:.3} ms, 99th percentile {:.3} ms, worst {:.3} ms; max length error {:.2e}, fail-safe steps {}, halved steps {}, asleep {} of {} particles",
                ms(times[300]),
                ms(times[594]),
                ms(times[599]),
                metrics.max_rel_length_error,
                metrics.failsafe_steps,
                metrics.halved_steps,
                metrics.asleep_particles,
                metrics.particles,
            );
            let id = BenchmarkId::new(name, format!("{threads}t settled"));
            group.bench_function(id, |b| b.iter(|| app.update()));
        }
    }
    group.finish();
}

criterion_group!(benches, frame);
criterion_main!(benches);
