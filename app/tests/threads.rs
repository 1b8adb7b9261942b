//! Determinism: a run's report is the same bit for bit on one thread and on two, and
//! from one run to the next.

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

/// The run `options(threads)` gives on one thread and on two: the same report.
fn same_on_one_and_two_threads(options: impl Fn(usize) -> RunOptions) -> Report {
    let one = run(&options(1), |_| {}).unwrap();
    let two = run(&options(2), |_| {}).unwrap();
    assert_eq!((one.threads, two.threads), (1, 2));
    assert_eq!(figures(&one), figures(&two));
    one
}

/// `scale` with `strands` strands of 100 particles for `seconds`, on one thread and
/// on two: the same report.
fn same_report_on_one_and_two_threads(strands: usize, seconds: f64) -> Report {
    let one = same_on_one_and_two_threads(|threads| RunOptions {
        scenario: "scale".into(),
        strands: Some(strands),
        particles: Some(100),
        seconds: Some(seconds),
        threads: Some(threads),
        check_crossings: true,
        ..Default::default()
    });
    assert!(
        one.max_rel_length_error < 1e-9,
        "{}",
        one.max_rel_length_error
    );
    one
}

#[test]
fn one_and_two_threads_give_the_same_report() {
    // 50 strands of 100 particles: enough edges (4 950) for the Constrain stage to
    // share its islands between threads; they land on the floor within the run.
    let report = same_report_on_one_and_two_threads(50, 0.15);
    assert!(
        report.constrained_edges >= 4096,
        "{}",
        report.constrained_edges
    );
    assert!(report.contacts > 0, "the strands reach the floor");
}

#[test]
fn the_point_queries_shared_between_threads_give_the_same_report() {
    // 170 strands of 100 (17 000 points and edges, many times the 4 096 at which the
    // point queries and the crossing check are shared); the lowest strands reach the
    // floor, so the pairs' order matters to the impulses.
    let report = same_report_on_one_and_two_threads(170, 0.15);
    assert!(report.particles >= 4 * 4096, "{}", report.particles);
    assert!(report.contacts > 0, "the strands reach the floor");
}

#[test]
fn a_rerun_gives_the_same_report_bit_for_bit() {
    // The factories: contact, the fail-safe's zones, emissions and withdrawals all in
    // one run; each run in a fresh app.
    for scenario in ["spaghetti_factory", "meatball_factory"] {
        let options = RunOptions {
            scenario: scenario.into(),
            seconds: Some(3.0),
            check_crossings: true,
            ..Default::default()
        };
        let first = run(&options, |_| {}).unwrap();
        let second = run(&options, |_| {}).unwrap();
        assert_eq!(figures(&first), figures(&second), "{scenario}");
        assert!(first.contacts > 0, "{scenario} reached contact");
    }
}

#[test]
fn the_contact_groups_shared_between_threads_give_the_same_report() {
    // The dense pile: thousands of contact rows a step in many independent groups,
    // projected on two lanes with two threads.
    let one = same_on_one_and_two_threads(|threads| RunOptions {
        scenario: "pile".into(),
        seconds: Some(0.3),
        threads: Some(threads),
        check_crossings: true,
        ..Default::default()
    });
    // More contact projections than steps: the steps' rows fell into several groups.
    assert!(
        one.contact_projection_solves > 2 * one.steps,
        "{} contact projections in {} steps",
        one.contact_projection_solves,
        one.steps
    );
    // Enough rows a step (on average) for the lanes to be used.
    assert!(one.contacts > 512 * one.steps, "{} contacts", one.contacts);
    assert_eq!(one.edge_crossings, Some(0));
    assert!(
        one.max_rel_length_error < 1e-12,
        "{:e}",
        one.max_rel_length_error
    );
}

#[test]
fn a_factorization_shared_between_threads_gives_the_same_report() {
    // The coiling rope by 0.7 s: one contact group, its factorizations large enough to
    // be cut into two runs of subtrees, one per thread.
    let one = same_on_one_and_two_threads(|threads| RunOptions {
        scenario: "rope_coil".into(),
        seconds: Some(0.7),
        threads: Some(threads),
        check_crossings: true,
        ..Default::default()
    });
    assert!(one.contact_projection_factorizations > 0);
    assert_eq!(one.edge_crossings, Some(0));
    assert!(
        one.max_rel_length_error < 1e-12,
        "{:e}",
        one.max_rel_length_error
    );
}

/// `--profile`'s markers only read the clock: a profiled run computes the same, and its
/// stages account for the ticks' wall time (each share finite, the tick's phases
/// together most of it and never more).
#[test]
fn a_profiled_run_computes_the_same_and_accounts_for_its_time() {
    let options = |profile| RunOptions {
        scenario: "long_strand".into(),
        seconds: Some(0.5),
        threads: Some(1),
        check_crossings: true,
        profile,
        ..Default::default()
    };
    let plain = run(&options(false), |_| {}).unwrap();
    let profiled = run(&options(true), |_| {}).unwrap();
    assert!(plain.stage_profile.is_empty());
    assert_eq!(figures(&plain), figures(&profiled));
    let shares = &profiled.stage_profile;
    assert!(
        shares
            .iter()
            .all(|s| s.seconds.is_finite() && s.seconds >= 0.0 && s.share.is_finite()),
        "{shares:?}"
    );
    let total = |prefix: &str| -> f64 {
        shares
            .iter()
            .filter(|s| s.stage.starts_with(prefix))
            .map(|s| s.share)
            .sum()
    };
    assert!(
        (0.5..=1.0 + 1e-9).contains(&total("tick:")),
        "the tick's phases: {shares:?}"
    );
    let steps = shares
        .iter()
        .find(|s| s.stage == "tick: steps")
        .unwrap()
        .share;
    assert!(
        total("step:") > 0.0 && total("step:") <= steps + 1e-9,
        "the step's stages within the steps' phase: {shares:?}"
    );
}
