//! Fuzzing, with a fixed seed so a failure reproduces: the scene parser on arbitrary
//! bytes and on a good scene with tokens spliced in (no panic; what it accepts runs
//! finite), and random strands under random run-time edits (no panic, no non-finite
//! value, no crossing, every edge at its length).

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::world::edit::{delete_particle, toggle_pin};
use bevy_strands_app::fixtures::*;
use bevy_strands_app::runner::headless_app;
use bevy_strands_app::scenario::Scenario;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

use bevy_strands::prelude::*;

const GOOD: &str = r#"(
    name: "fuzz",
    duration: 1.0,
    step: (dt: 0.002, substeps: 2),
    container: Some((min: (0.0, 0.0), max: (1.0, 1.0))),
    strands: [
        (shape: Line(start: (0.1, 0.5), angle_degrees: 10.0, particles: 10, spacing: 0.05), pinned: [0]),
        (shape: Polyline(points: [(0.1, 0.2), (0.2, 0.2), (0.3, 0.25)]), mass: 2.0),
    ],
    links: [(from: (0, 9), to: (1, 2))],
    particles: [(position: (0.5, 0.7), velocity: (1.0, 0.0))],
)"#;

/// Numbers out of range, in range and at the edges.
const NUMBERS: &[&str] = &[
    "-1", "1e308", "-1e308", "NaN", "inf", "-inf", "1e-300", "0", "0.0", "2.0", "-0.5", "1e10",
    "3", "0.999", "1.0", "0.001",
];

fn runner(cases: u32) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha))
}

/// Every packed position and velocity finite, and the guard silent.
fn assert_finite(app: &App) {
    let state = app.world().resource::<ParticleState>();
    assert!(
        state
            .position
            .iter()
            .chain(&state.velocity)
            .all(|v| v.is_finite())
    );
}

#[test]
fn arbitrary_bytes_never_panic_the_parser() {
    runner(512)
        .run(&proptest::collection::vec(any::<u8>(), 0..600), |bytes| {
            let text = String::from_utf8_lossy(&bytes);
            let _ = Scenario::parse(&text, "fuzz.ron");
            Ok(())
        })
        .unwrap();
}

#[test]
fn a_good_scene_with_numbers_replaced_is_refused_or_runs_finite() {
    // Where each number of the good scene starts and ends.
    let bytes = GOOD.as_bytes();
    let numeric = |i: usize| bytes[i].is_ascii_digit() || bytes[i] == b'.' || bytes[i] == b'-';
    let spans: Vec<(usize, usize)> = (0..bytes.len())
        .filter(|&i| numeric(i) && (i == 0 || !numeric(i - 1) && bytes[i - 1] != b'_'))
        .map(|i| {
            (
                i,
                (i..bytes.len())
                    .find(|&j| !numeric(j))
                    .unwrap_or(bytes.len()),
            )
        })
        .collect();
    let replace = proptest::collection::vec((0..spans.len(), 0..NUMBERS.len()), 1..3);
    let accepted = std::cell::Cell::new(0);
    runner(256)
        .run(&replace, |edits| {
            let mut chosen: Vec<(usize, usize)> = edits;
            chosen.sort_unstable();
            chosen.dedup_by_key(|(span, _)| *span);
            let mut text = GOOD.to_string();
            // From the last so earlier spans stay where they were.
            for &(span, number) in chosen.iter().rev() {
                let (start, end) = spans[span];
                text.replace_range(start..end, NUMBERS[number]);
            }
            let Ok(scene) = Scenario::parse(&text, "fuzz.ron") else {
                return Ok(());
            };
            let Ok(mut app) = headless_app(&scene) else {
                return Ok(());
            };
            accepted.set(accepted.get() + 1);
            app.world_mut().resource_mut::<StrandsConfig>().substeps = 1;
            for _ in 0..5 {
                tick(&mut app);
                assert_finite(&app);
            }
            Ok(())
        })
        .unwrap();
    // Many replacements are refused; many must get through to the simulation.
    let accepted = accepted.get();
    assert!(accepted > 20, "only {accepted} scenes ran");
}

/// A run-time edit: what, and two numbers choosing its target and its amount.
#[derive(Clone, Copy, Debug)]
struct Edit {
    op: u8,
    a: u16,
    b: u16,
}

fn edit() -> impl Strategy<Value = Edit> {
    (0u8..5, any::<u16>(), any::<u16>()).prop_map(|(op, a, b)| Edit { op, a, b })
}

/// A strand in lane `lane` of the unit box: rows 0.13 apart, so no two start within
/// reach of each other. A slight zigzag keeps a span between two pins from being
/// pulled exactly straight, where the constraints are dependent (see the closing of
/// the test).
fn lane_strand(lane: usize, particles: usize, spacing: f64, x0: f64) -> StrandBuilder {
    let y = 0.12 + 0.13 * lane as f64;
    let points = (0..particles).map(|i| {
        let zig = if i % 2 == 0 { 0.0 } else { 0.2 * spacing };
        DVec2::new(x0 + spacing * i as f64, y + zig)
    });
    StrandBuilder::polyline(points).kind(StrandKind::Rope)
}

/// The particles edits may touch: every one of a strand that is not a wall, in a fixed
/// order.
fn editable(app: &mut App) -> Vec<Entity> {
    let world = app.world_mut();
    let mut query = world.query::<(Entity, &StrandOf)>();
    let mut particles: Vec<Entity> = query
        .iter(world)
        .filter(|(_, of)| world.get::<StrandKind>(of.0) != Some(&StrandKind::Wall))
        .map(|(p, _)| p)
        .collect();
    particles.sort();
    particles
}

fn apply(app: &mut App, edit: Edit, lanes_used: &mut usize) {
    let particles = editable(app);
    let pick = |n: u16| particles.get(n as usize % particles.len().max(1)).copied();
    let world = app.world_mut();
    match edit.op {
        0 => {
            if let Some(p) = pick(edit.a) {
                toggle_pin(world, p).unwrap();
            }
        }
        1 => {
            if let Some(p) = pick(edit.a) {
                delete_particle(world, p).unwrap();
            }
        }
        2 => {
            // Drag a free particle at up to 3 m/s.
            if let Some(p) = pick(edit.a).filter(|&p| world.get::<Pinned>(p).is_none()) {
                let angle = edit.b as f64 / 65536.0 * std::f64::consts::TAU;
                let speed = 3.0 * (edit.a % 7) as f64 / 6.0;
                world
                    .entity_mut(p)
                    .insert(Velocity(speed * DVec2::from_angle(angle)));
            }
        }
        3 => {
            if let Some(strand) = pick(edit.a).and_then(|p| world.get::<StrandOf>(p)) {
                world.entity_mut(strand.0).despawn();
            }
        }
        _ => {
            // A new strand in the next empty lane at the top, if nothing is near it.
            let lane = *lanes_used;
            let y = 0.12 + 0.13 * lane as f64;
            let mut positions = world.query::<&Position>();
            let clear = positions.iter(world).all(|x| (x.0.y - y).abs() > 0.06);
            if lane < 7 && clear {
                let n = 3 + (edit.a % 10) as usize;
                lane_strand(lane, n, 0.02 + (edit.b % 4) as f64 * 0.01, 0.1)
                    .spawn_in(world)
                    .unwrap();
                *lanes_used += 1;
            }
        }
    }
}

#[test]
fn random_strands_under_random_edits_stay_exact_and_never_cross() {
    let strand = (
        3usize..12,
        0.02f64..0.05,
        0.05f64..0.4,
        proptest::collection::vec(0usize..12, 0..3),
    );
    let scene = (
        proptest::collection::vec(strand, 1..5),
        proptest::collection::vec(edit(), 0..12),
    );
    runner(24)
        .run(&scene, |(strands, edits)| {
            let mut app = checked_app();
            set_step(&mut app, 1.0 / 600.0, 2);
            spawn_box(&mut app);
            let mut lanes_used = strands.len();
            for (lane, (n, spacing, x0, pins)) in strands.into_iter().enumerate() {
                let mut builder = lane_strand(lane, n, spacing, x0);
                for pin in pins.into_iter().filter(|&p| p < n) {
                    builder = builder.pin(pin);
                }
                builder.spawn_in(app.world_mut()).unwrap();
            }
            // Ticks, then an edit, then ticks again; the figures after each.
            for k in 0..=edits.len() {
                if k > 0 {
                    apply(&mut app, edits[k - 1], &mut lanes_used);
                }
                let edit = edits.get(k.wrapping_sub(1));
                for _ in 0..4 {
                    tick(&mut app);
                    assert_finite(&app);
                }
                let metrics = app.world().resource::<StrandMetrics>();
                prop_assert_eq!(crossings(&app), 0, "after edit {} ({:?})", k, edit);
                prop_assert!(
                    metrics.max_rel_length_error <= 1e-9,
                    "length error {:e} after edit {} ({:?})",
                    metrics.max_rel_length_error,
                    k,
                    edit
                );
                prop_assert!(app.world().resource::<FiniteGuard>().events.is_empty());
            }
            Ok(())
        })
        .unwrap();
}
