//! Rows settle: a dropped pile comes to rest, its edges exact. The contact Newton
//! meets every row exactly and the pile stops dead; the sweeps meet a resting group's
//! rows to a hundredth of a thickness per second (at their usual tolerance, a
//! thickness per second, friction kept the pile creeping at about a millimetre per
//! second, and the full pile trembling at centimetres).

use bevy_strands::prelude::*;
use bevy_strands_app::fixtures::ticks;
use bevy_strands_app::runner::{RunOptions, headless_app, load_scenario};

/// The median speed of the free particles.
fn median_speed(state: &ParticleState) -> f64 {
    let mut speeds: Vec<f64> = (state.velocity.iter().zip(&state.inverse_mass))
        .filter(|(_, w)| **w > 0.0)
        .map(|(v, _)| v.length())
        .collect();
    speeds.sort_by(f64::total_cmp);
    speeds[speeds.len() / 2]
}

#[test]
fn a_dropped_pile_comes_to_rest() {
    // The built-in pile's bottom rows: 45 strands of 15 particles dropped at once,
    // three seconds on (measured: the Newton's median 1.5e-13 m/s from the first
    // second on; the sweeps' 0.5 to 1.3 mm/s from then to six seconds before groups at
    // rest were met closely).
    for (solver, bound) in [
        (ContactSolver::Newton, 1e-9),
        (ContactSolver::GaussSeidel, 1e-4),
    ] {
        let mut scenario = load_scenario(&RunOptions {
            scenario: "pile".into(),
            strands: Some(45),
            ..Default::default()
        })
        .unwrap();
        scenario.contact.solver = solver;
        // How far the solvers themselves bring the pile to rest: awake.
        scenario.step.sleep.enabled = false;
        let mut app = headless_app(&scenario).unwrap();
        // Three steps a tick: three seconds.
        ticks(&mut app, 300);
        let median = median_speed(app.world().resource::<ParticleState>());
        assert!(median < bound, "{solver:?}: median speed {median} m/s");
        let metrics = app.world().resource::<StrandMetrics>();
        assert!(
            metrics.max_rel_length_error < 1e-12,
            "{solver:?}: {:e}",
            metrics.max_rel_length_error
        );
    }
}
