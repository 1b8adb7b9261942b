//! The first crossing of the 100 s spaghetti factory run, kept from coming back.
//!
//! `data/spaghetti_factory_67.15s.ron` is the run's state at t = 67.15 s (step 201 450),
//! taken by `strands run spaghetti_factory --seconds 67.15 --snapshot-at 67.15`. Deep in
//! the pile a particle then lay 1e-13 off another strand's edge, squeezed against it by
//! a third strand: collisions resolved it to zero gap, and sixteen steps later, moving
//! 1e-14 per step with the edge, it ended a step across the edge's line without the
//! continuous detection seeing it (its collinearity quadratic was within the
//! degenerate-case tolerance). Collisions now leave pairs apart by the separation, and
//! a point ending across a line is always a collision.

use std::path::PathBuf;

use bevy_strands_app::runner::{RunOptions, run};

#[test]
fn the_pile_of_the_100_s_factory_run_passes_its_first_crossing_untouched() {
    let snapshot =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/spaghetti_factory_67.15s.ron");
    let report = run(
        &RunOptions {
            from: Some(snapshot),
            // 300 steps: the crossing was at the 16th.
            seconds: Some(67.25),
            check_crossings: true,
            ..Default::default()
        },
        |_| {},
    )
    .expect("the snapshot restores and runs");
    assert_eq!(report.steps, 201_750);
    assert_eq!(
        report.edge_crossings,
        Some(0),
        "{:?}",
        report.first_crossing
    );
    // The figures so far came with the snapshot: the run's own maxima are kept.
    assert!(
        report.max_rel_length_error < 1e-9,
        "{:e}",
        report.max_rel_length_error
    );
}
