//! Criterion benchmarks of the two bending models on 1000 strands of 100 particles
//! (98 000 bending vertices), per step: the angle model's explicit forces, the
//! quadratic model's explicit forces (a sparse matrix–vector product), and the
//! quadratic model's implicit predictor (one sparse LDLᵀ solve), with the factorization
//! it needs once per topology change timed apart.
//!
//! Run with `cargo bench --bench bending`; results are recorded in `benches/RESULTS.md`.

use std::hint::black_box;

use bevy::math::DVec2;
use bevy_strands::forces::bending::add_bending;
use bevy_strands::forces::implicit_bending::ImplicitBending;
use bevy_strands::forces::quadratic_bending::add_quadratic_bending;
use bevy_strands::model::Bend;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

const STRANDS: usize = 1000;
const PARTICLES: usize = 100;
const SPACING: f64 = 0.01;

/// The bends and particle arrays of the benchmark's strands.
struct Hairs {
    bends: Vec<Bend>,
    position: Vec<DVec2>,
    velocity: Vec<DVec2>,
    mass: Vec<f64>,
    inverse_mass: Vec<f64>,
}

/// Curly strands with exact edge lengths, their first particle pinned.
fn hairs() -> Hairs {
    let mut rng = StdRng::seed_from_u64(7);
    let (mut bends, mut position, mut velocity) = (Vec::new(), Vec::new(), Vec::new());
    let (mut mass, mut inverse_mass) = (Vec::new(), Vec::new());
    for strand in 0..STRANDS {
        let first = (strand * PARTICLES) as u32;
        let mut x = DVec2::new(strand as f64 * 0.05, 0.0);
        let mut heading: f64 = 1.5;
        for i in 0..PARTICLES {
            position.push(x);
            velocity.push(DVec2::new(
                rng.random_range(-0.1..0.1),
                rng.random_range(-0.1..0.1),
            ));
            mass.push(1e-3);
            inverse_mass.push(if i == 0 { 0.0 } else { 1e3 });
            heading += rng.random_range(-0.2..0.2);
            x += SPACING * DVec2::from_angle(heading);
        }
        for s in 1..PARTICLES as u32 - 1 {
            bends.push(Bend {
                a: first + s - 1,
                s: first + s,
                b: first + s + 1,
                rest_angle: rng.random_range(-0.1..0.1),
                stiffness: 2e-3 / SPACING,
                damping: 1e-5,
                rest_lengths: [SPACING, SPACING],
            });
        }
    }
    Hairs {
        bends,
        position,
        velocity,
        mass,
        inverse_mass,
    }
}

fn bending(c: &mut Criterion) {
    let Hairs {
        bends,
        position,
        velocity,
        mass,
        inverse_mass,
    } = hairs();
    let dt = 1.0 / 300.0;
    let mut group = c.benchmark_group("bending");
    group.throughput(Throughput::Elements(bends.len() as u64));
    let mut force = vec![DVec2::ZERO; position.len()];
    group.bench_function("angle_forces", |b| {
        b.iter(|| add_bending(&bends, &position, &velocity, black_box(&mut force)))
    });
    group.bench_function("quadratic_forces", |b| {
        b.iter(|| add_quadratic_bending(&bends, &position, &velocity, black_box(&mut force)))
    });
    let mut solver = ImplicitBending::default();
    group.bench_function("quadratic_factor", |b| {
        b.iter(|| solver.build(&bends, &mass, &inverse_mass, dt).unwrap())
    });
    // Built here too: the predictor must not depend on the factor's benchmark having run.
    solver.build(&bends, &mass, &inverse_mass, dt).unwrap();
    let force = vec![DVec2::new(0.0, -9.81e-3); position.len()];
    let mut next = velocity.clone();
    group.bench_function("quadratic_implicit_predict", |b| {
        b.iter(|| {
            next.copy_from_slice(&velocity);
            solver.predict(
                &bends,
                &position,
                black_box(&mut next),
                &force,
                &inverse_mass,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, bending);
criterion_main!(benches);
