//! Hard motion away from contact stays exact at every step size: a heavy bob on a
//! light rope, and a whip turning through large angles within a step. Where one
//! projection does not converge the island is re-stepped, and the motion it keeps is
//! the motion a fine step gives.

use bevy_strands::prelude::*;
use bevy_strands_app::energy::EnergyLedger;
use bevy_strands_app::fixtures::ticks;
use bevy_strands_app::free::FreeSpeeds;
use bevy_strands_app::runner::{RunOptions, headless_app, load_scenario};

/// Run built-in `name` at `dt` (one step a tick) for `seconds`; the times at which the
/// heaviest particle crosses the pin's vertical (x = 0.5) moving right, and the metrics.
fn swing(name: &str, dt: f64, seconds: f64) -> (Vec<f64>, StrandMetrics) {
    let scenario = load_scenario(&RunOptions {
        scenario: name.into(),
        dt: Some(dt),
        substeps: Some(1),
        check_crossings: true,
        ..Default::default()
    })
    .unwrap();
    let mut app = headless_app(&scenario).unwrap();
    let bob = {
        let state = app.world().resource::<ParticleState>();
        (0..state.len())
            .max_by(|&a, &b| state.mass[a].total_cmp(&state.mass[b]))
            .unwrap()
    };
    let (mut times, mut previous) = (Vec::new(), f64::NAN);
    let steps = (seconds / dt).round() as usize;
    for k in 1..=steps {
        ticks(&mut app, 1);
        let x = app.world().resource::<ParticleState>().position[bob].x - 0.5;
        if previous < 0.0 && x >= 0.0 {
            times.push((k as f64 - x / (x - previous)) * dt);
        }
        previous = x;
    }
    (times, app.world().resource::<StrandMetrics>().clone())
}

fn period(times: &[f64]) -> f64 {
    assert!(times.len() >= 3, "no swing: {times:?}");
    (times[times.len() - 1] - times[0]) / (times.len() - 1) as f64
}

#[test]
fn a_heavy_pendulum_keeps_its_period_at_every_step() {
    // Let go 30° from the vertical. Measured: 1.30612 s at 1/3000, 1.30405 s at 1/300
    // (−0.16 %), 1.30477 s at 1/60 (−0.10 %); every edge within 5.1e-13, no step in the
    // fail-safe.
    let (fine, metrics) = swing("pendulum_1e4", 1.0 / 3000.0, 10.0);
    let reference = period(&fine);
    assert!(metrics.max_rel_length_error < 1e-12);
    for dt in [1.0 / 300.0, 1.0 / 60.0] {
        let (times, metrics) = swing("pendulum_1e4", dt, 10.0);
        let p = period(&times);
        assert!(
            (p / reference - 1.0).abs() < 5e-3,
            "1/{:.0}: {p} s against {reference} s",
            1.0 / dt
        );
        assert!(metrics.max_rel_length_error < 1e-9, "{metrics:?}");
        assert_eq!(metrics.failsafe_steps, 0);
        assert_eq!(metrics.edge_crossings, Some(0));
        assert_eq!(metrics.projection.capped, 0);
        assert!(metrics.projection.restepped > 0);
    }
}

#[test]
fn a_million_to_one_pendulum_and_a_whip_stay_exact_at_a_game_step() {
    for name in ["pendulum_1e6", "whip"] {
        let (_, metrics) = swing(name, 1.0 / 60.0, 2.0);
        assert!(metrics.max_rel_length_error < 1e-9, "{name}: {metrics:?}");
        assert_eq!(metrics.projection.capped, 0, "{name}");
        assert_eq!(metrics.failsafe_steps, 0, "{name}");
        assert_eq!(metrics.edge_crossings, Some(0), "{name}");
    }
}

/// `long_strand` at 1/60, one step a tick, with the explicit bending it was built with,
/// for 3 s, with `halvings` and `split` ahead: its metrics, its clock, the most its
/// energy rose above its lowest so far, and its free particles' fastest speed at the
/// end.
fn explicit_long_strand_at_a_games_step(
    halvings: u32,
    split: u32,
) -> (StrandMetrics, SimulationClock, f64, f64) {
    let mut scenario = load_scenario(&RunOptions {
        scenario: "long_strand".into(),
        dt: Some(1.0 / 60.0),
        substeps: Some(1),
        check_crossings: true,
        ..Default::default()
    })
    .unwrap();
    scenario.step.bending = BendingModel::AngleExplicit;
    // Its rows met to the whole step's shortfall, five times a 1/300 s step's (the
    // tolerance is bounded at a 1/300 s step's by default, which spares this landing
    // the fail-safe it is here to show).
    scenario.contact.tolerance *= 5.0;
    let mut app = headless_app(&scenario).unwrap();
    let mut config = app.world_mut().resource_mut::<StrandsConfig>();
    config.max_step_halvings = halvings;
    config.max_split_ahead = split;
    let mut ledger = EnergyLedger::default();
    for _ in 0..180 {
        ticks(&mut app, 1);
        ledger.observe(app.world());
    }
    let world = app.world();
    let clock = *world.resource::<SimulationClock>();
    let fastest = FreeSpeeds::of(world).quantile(1.0);
    let metrics = world.resource::<StrandMetrics>().clone();
    (metrics, clock, ledger.largest_rise, fastest)
}

#[test]
fn a_step_that_would_end_in_the_fail_safe_is_taken_again_in_halves() {
    // Its landing ends one step in the fail-safe unless that step is taken as two of
    // 1/120 (measured: 1 halved step, no fail-safe step). With the implicit angle model
    // it needs neither. Splitting ahead off: halving alone.
    let (without, ..) = explicit_long_strand_at_a_games_step(0, 0);
    assert!(without.failsafe_steps > 0, "{without:?}");
    assert_eq!(without.halved_steps, 0);
    let (with, clock, ..) = explicit_long_strand_at_a_games_step(2, 0);
    assert_eq!(with.failsafe_steps, 0, "{with:?}");
    assert!(with.halved_steps > 0);
    assert_eq!(with.split_steps, 0);
    assert!(with.max_rel_length_error < 1e-12, "{with:?}");
    assert_eq!(with.edge_crossings, Some(0));
    // The halves add up to the steps they replace.
    assert!((clock.time - 3.0).abs() < 1e-9, "{clock:?}");
}

#[test]
fn steps_after_a_hard_one_are_split_ahead_and_grow_back_whole() {
    // The same landing with splitting ahead: the steps after the first hard one are
    // taken in parts from the start, so none needs the fail-safe, and once the strand
    // lies still they are whole again. The parts add up to the clock's steps.
    let (metrics, clock, rise, fastest) = explicit_long_strand_at_a_games_step(2, 2);
    let (_, _, halved_rise, halved_fastest) = explicit_long_strand_at_a_games_step(2, 0);
    eprintln!(
        "{metrics:?}\nenergy rise {rise} J, fastest at the end {fastest} m/s (halving \
         alone: {halved_rise} J, {halved_fastest} m/s)"
    );
    assert_eq!(metrics.failsafe_steps, 0, "{metrics:?}");
    assert!(metrics.split_steps > 0, "{metrics:?}");
    // Split only around the landing, not for the rest of the run.
    assert!(
        metrics.split_steps < 90,
        "{} of 180 split",
        metrics.split_steps
    );
    assert!(metrics.max_rel_length_error < 1e-12, "{metrics:?}");
    assert_eq!(metrics.edge_crossings, Some(0));
    assert_eq!(clock.steps, 180);
    assert!((clock.time - 3.0).abs() < 1e-9, "{clock:?}");
    // The parts put in no energy the halved steps did not, and the strand ends at rest
    // (asleep, as by default).
    assert!(rise <= halved_rise, "{rise} J against {halved_rise} J");
    assert!(fastest < 1e-2, "{fastest} m/s");
}
