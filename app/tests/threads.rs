//! Threads: a run's report is the same bit for bit on one thread and on two.

use bevy_strands_app::report::Report;
use bevy_strands_app::runner::{RunOptions, run};

/// Every field of the report but those the wall clock measures (the thread count
/// among them).
fn figures(report: &Report) -> serde_json::Value {
    let mut value = serde_json::to_value(report).unwrap();
    let object = value.as_object_mut().unwrap();
    for key in Report::WALL_CLOCK_FIELDS {
        object.remove(key);
    }
    value
}

#[test]
fn one_and_two_threads_give_the_same_report() {
    // 50 strands of 100 particles: enough edges (4 950) for the Constrain stage to
    // share its islands between threads; they land on the floor within the run.
    let options = |threads| RunOptions {
        scenario: "scale".into(),
        strands: Some(50),
        particles: Some(100),
        seconds: Some(0.15),
        threads: Some(threads),
        check_crossings: true,
        ..Default::default()
    };
    let one = run(&options(1), |_| {}).unwrap();
    let two = run(&options(2), |_| {}).unwrap();
    assert!(one.constrained_edges >= 4096, "{}", one.constrained_edges);
    assert!(one.collisions > 0, "the strands reach the floor");
    assert_eq!((one.threads, two.threads), (1, 2));
    assert_eq!(figures(&one), figures(&two));
    assert!(
        one.max_rel_length_error < 1e-9,
        "{}",
        one.max_rel_length_error
    );
}
