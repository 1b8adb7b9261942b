//! Criterion benchmark of one rope resting in a coil on the floor: 250, 1 000 and 4 000
//! particles, three layers high, on a floor that grows with the rope, so that every
//! contact row has the same neighbourhood and only the strand's length changes. A
//! tick is three steps of 1/300 s, one second after the drop (the layers have landed).
//! The throughput is in particle-steps: a solve whose rows cost a whole strand would
//! lose a factor 16 from the shortest rope to the longest. Run with
//! `cargo bench --bench coil`; results per machine are in `benches/RESULTS.md`.

use std::time::Duration;

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::fixtures::{tick, ticks};
use bevy_strands_app::runner::headless_app;
use bevy_strands_app::scenario::Scenario;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

const LAYER_GAP: f64 = 0.006;
const SPACING: f64 = 0.01;

/// The scene: a serpentine of three rows 6 mm apart (2 mm of air between 4 mm thick
/// strands), the lowest row 4.5 mm above the floor, in a box 10 cm wider than a row.
fn resting_coil(particles: usize) -> Scenario {
    let per_row = particles.div_ceil(3) - 1;
    let width = (per_row - 1) as f64 * SPACING;
    let top = 0.0045 + 2.0 * LAYER_GAP;
    let text = format!(
        r#"(
    name: "coil_{particles}",
    description: "a rope of {particles} particles resting in three layers",
    duration: 2.0,
    step: (
        dt: 0.0033333333333333335,
        substeps: 3,
        gravity: (0.0, -9.81),
        damping: 0.0,
        material: (stretch_stiffness: 1.0e4, stretch_damping: 5.0, bending_stiffness: 1.0e-3, bending_damping: 1.0e-5),
    ),
    constraints: (solver: "tridiagonal"),
    collisions: (enabled: true, thickness: 0.004, friction: 0.3, restitution: 0.0),
    container: Some((min: (0.0, 0.0), max: ({right}, 1.0))),
    strands: [(
        shape: Serpentine(start: (0.05, {top}), width: {width}, row_gap: {LAYER_GAP}, particles: {particles}, spacing: {SPACING}),
        kind: Spaghetti,
    )],
)"#,
        right = 0.1 + width,
    );
    Scenario::parse(&text, "coil").expect("the coil scene parses")
}

fn coil_tick(c: &mut Criterion) {
    let mut group = c.benchmark_group("coil_tick");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for particles in [250usize, 1000, 4000] {
        let scenario = resting_coil(particles);
        for threads in [1usize, 2] {
            let mut app = headless_app(&scenario).expect("the coil spawns");
            app.world_mut().resource_mut::<StrandsConfig>().threads = threads;
            ticks(&mut app, 100);
            let substeps = u64::from(scenario.step.substeps);
            let count = app.world().resource::<ParticleState>().len();
            group.throughput(Throughput::Elements(count as u64 * substeps));
            let id = BenchmarkId::new(particles.to_string(), format!("{threads}t"));
            group.bench_function(id, |b| b.iter(|| tick(&mut app)));
        }
    }
    group.finish();
}

criterion_group!(benches, coil_tick);
criterion_main!(benches);
