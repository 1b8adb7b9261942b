//! Criterion benchmark of what sharing a stage between threads costs before any work
//! is done: `run_each` over two empty parts (a scoped thread started and joined, as
//! every shared stage does), one empty part (no thread: the floor), a `with_partner`
//! scope with no job (the contact sweeps start one per Newton step) and one job's
//! round trip through a running partner (each shared sweep hands one over). A stage
//! gains from a second thread only when its work is well above the first figure. Run
//! with `cargo bench --bench threads`; results per machine are in `benches/RESULTS.md`.

use std::hint::black_box;
use std::time::Duration;

use bevy_strands::parallel::{run_each, with_partner};
use criterion::{Criterion, criterion_group, criterion_main};

fn sharing(c: &mut Criterion) {
    let mut group = c.benchmark_group("sharing");
    group
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    group.bench_function("run_each/1 part", |b| {
        b.iter(|| run_each(vec![black_box(1u64)], |i, x| x + i as u64))
    });
    group.bench_function("run_each/2 parts", |b| {
        b.iter(|| run_each(vec![black_box(1u64), 2], |i, x| x + i as u64))
    });
    group.bench_function("with_partner/no job", |b| {
        b.iter(|| with_partner(|x: u64| x + 1, |_| black_box(0u64)))
    });
    with_partner(
        |x: u64| x + 1,
        |partner| {
            group.bench_function("with_partner/one job", |b| {
                b.iter(|| {
                    partner.send(black_box(1));
                    partner.wait()
                })
            });
        },
    );
    group.finish();
}

criterion_group!(benches, sharing);
criterion_main!(benches);
