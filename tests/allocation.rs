//! A steady-state step allocates nothing, measured with a counting global
//! allocator. This file is its own test binary so the counter sees only this test.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::runner::{RunOptions, headless_app, load_scenario};

struct CountingAllocator;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

fn allocations_during(f: impl FnOnce()) -> u64 {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    f();
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

#[test]
fn steady_state_steps_and_ticks_allocate_nothing() {
    // Chains (Thomas) in long_strand; trees and graphs (sparse LDLᵀ) in branches.
    for scenario in ["long_strand", "branches"] {
        steady_state_allocates_nothing(scenario);
    }
}

fn steady_state_allocates_nothing(scenario: &str) {
    let scene = load_scenario(&RunOptions {
        scenario: scenario.into(),
        ..Default::default()
    })
    .unwrap();
    let mut app = headless_app(&scene).unwrap();
    let world = app.world_mut();
    // With the end-of-step crossing check, as the runner's reports have it.
    world.resource_mut::<CollisionConfig>().check_crossings = true;
    // The counter works: one allocation is seen.
    let probe = allocations_during(|| {
        std::hint::black_box(Vec::<u8>::with_capacity(16));
    });
    assert_eq!(probe, 1);
    // Warm up through first contact (3 s): the first ticks build the topology, the
    // islands and the schedules; the first contacts size the collision and contact
    // buffers (long_strand's strands settling on each other reach their peak of
    // contact rows a little after 2 s).
    for _ in 0..300 {
        world.run_schedule(StrandsTick);
    }
    let steps = allocations_during(|| {
        for _ in 0..300 {
            world.run_schedule(StrandsStep);
        }
    });
    assert_eq!(steps, 0, "{scenario}: allocations in 300 steps");
    let ticks = allocations_during(|| {
        for _ in 0..10 {
            world.run_schedule(StrandsTick);
        }
    });
    assert_eq!(ticks, 0, "{scenario}: allocations in 10 ticks");
}
