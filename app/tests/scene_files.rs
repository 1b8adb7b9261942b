//! Scenario files: the built-in scenarios load, and every kind of bad input is refused with
//! a message naming the file, the item and the problem.

use bevy_strands_app::builtin::BUILTIN_SCENES;
use bevy_strands_app::runner::{RunError, RunOptions, headless_app, load_scenario};
use bevy_strands_app::scenario::Scenario;

const GOOD: &str = r#"(
    name: "test",
    duration: 1.0,
    step: (dt: 0.001, substeps: 10),
    container: Some((min: (0.0, 0.0), max: (1.0, 1.0))),
    strands: [
        (shape: Line(start: (0.1, 0.5), angle_degrees: 0.0, particles: 10, spacing: 0.05)),
        (shape: Polyline(points: [(0.1, 0.2), (0.2, 0.2), (0.3, 0.25)]), mass: 2.0),
    ],
    particles: [(position: (0.5, 0.7))],
)"#;

fn rejected(text: &str) -> String {
    match Scenario::parse(text, "bad.ron") {
        Ok(_) => panic!("scene was accepted:\n{text}"),
        Err(e) => {
            let message = e.to_string();
            assert!(message.starts_with("bad.ron: "), "{message}");
            message
        }
    }
}

/// `text` written to a file of this test process's own.
fn scene_file(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("bevy_strands_scenes_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join(name);
    std::fs::write(&file, text).unwrap();
    file
}

#[test]
fn builtin_scenes_are_valid() {
    for scene in BUILTIN_SCENES {
        let parsed = scene.scenario().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(parsed.name, scene.name);
    }
}

#[test]
fn a_good_scene_parses() {
    let scene = Scenario::parse(GOOD, "good.ron").unwrap();
    assert_eq!(scene.strands.len(), 2);
}

#[test]
fn nan_and_infinite_numbers_are_rejected() {
    let message = rejected(&GOOD.replace("start: (0.1, 0.5)", "start: (NaN, 0.5)"));
    assert!(message.contains("strands[0].shape.start") && message.contains("not finite"));
    let message = rejected(&GOOD.replace("(0.2, 0.2)", "(0.2, inf)"));
    assert!(message.contains("strands[1].shape.points[1]") && message.contains("not finite"));
    let message = rejected(&GOOD.replace("dt: 0.001", "dt: inf"));
    assert!(message.contains("dt") && message.contains("positive and finite"));
}

#[test]
fn non_positive_masses_are_rejected() {
    let message = rejected(&GOOD.replace("mass: 2.0", "mass: -2.0"));
    assert!(
        message.contains("strands[1].mass: -2 must be positive"),
        "{message}"
    );
    let message = rejected(&GOOD.replace(
        "(position: (0.5, 0.7))",
        "(position: (0.5, 0.7), mass: 0.0)",
    ));
    assert!(message.contains("particles[0].mass"), "{message}");
}

#[test]
fn a_strand_of_fewer_than_two_particles_is_rejected() {
    let message = rejected(&GOOD.replace("particles: 10", "particles: 1"));
    assert!(message.contains("strands[0].shape.particles") && message.contains("at least 2"));
    let message = rejected(&GOOD.replace("[(0.1, 0.2), (0.2, 0.2), (0.3, 0.25)]", "[(0.1, 0.2)]"));
    assert!(
        message.contains("strands[1]") && message.contains("at least 2"),
        "{message}"
    );
}

#[test]
fn zero_or_negative_rest_lengths_are_rejected() {
    let message = rejected(&GOOD.replace("spacing: 0.05", "spacing: 0.0"));
    assert!(message.contains("strands[0].shape.spacing") && message.contains("rest length"));
    let message =
        rejected(&GOOD.replace("mass: 2.0", "mass: 2.0, rest_lengths: Some([0.1, -0.1])"));
    assert!(
        message.contains("strands[1]") && message.contains("rest length of edge 1"),
        "{message}"
    );
}

#[test]
fn coincident_consecutive_particles_are_rejected() {
    let message = rejected(&GOOD.replace("(0.2, 0.2), (0.3, 0.25)", "(0.2, 0.2), (0.2, 0.2)"));
    assert!(
        message.contains("strands[1]") && message.contains("particles 1 and 2 coincide"),
        "{message}"
    );
}

#[test]
fn links_must_name_two_existing_separate_particles_once() {
    let with_links = |links: &str| {
        GOOD.replace(
            "particles: [(",
            &format!("links: [{links}],\n    particles: [("),
        )
    };
    let good = Scenario::parse(&with_links("(from: (0, 9), to: (1, 0))"), "good.ron").unwrap();
    assert_eq!(good.links.len(), 1);
    let message = rejected(&with_links("(from: (0, 1), to: (2, 0))"));
    assert!(
        message.contains("links[0].to: strand 2 does not exist; the scene has 2 strands"),
        "{message}"
    );
    let message = rejected(&with_links("(from: (0, 10), to: (1, 0))"));
    assert!(
        message.contains("links[0].from: strand 0 has no particle 10; it has 10"),
        "{message}"
    );
    // Neighbours along a strand are joined by its own edge already.
    let message = rejected(&with_links("(from: (0, 4), to: (0, 3))"));
    assert!(
        message.contains(
            "links[0]: joins particles 3 and 4 of strand 0, which an edge of that strand \
             already joins"
        ),
        "{message}"
    );
    assert!(Scenario::parse(&with_links("(from: (0, 2), to: (0, 4))"), "ok.ron").is_ok());
    // A loop's last particle is joined to its first; an open strand's is not.
    let looped = |links: &str| {
        with_links(links).replace(
            "Polyline(points: [(0.1, 0.2)",
            "Polygon(points: [(0.1, 0.2)",
        )
    };
    let message = rejected(&looped("(from: (1, 0), to: (1, 2))"));
    assert!(
        message.contains("joins particles 0 and 2 of strand 1"),
        "{message}"
    );
    assert!(Scenario::parse(&with_links("(from: (1, 0), to: (1, 2))"), "ok.ron").is_ok());
    let message = rejected(&with_links("(from: (1, 2), to: (1, 2))"));
    assert!(
        message.contains("links[0]: an edge needs two different particles"),
        "{message}"
    );
    // Particle 2 of strand 0 sits at (0.2, 0.5); a new strand puts its first there too.
    let coincident = with_links("(from: (0, 2), to: (2, 0))").replace(
        "mass: 2.0),",
        "mass: 2.0),\n        (shape: Polyline(points: [(0.2, 0.5), (0.2, 0.6)])),",
    );
    let message = rejected(&coincident);
    assert!(
        message.contains("links[0]: its particles coincide")
            && message.contains("zero rest length"),
        "{message}"
    );
    let message = rejected(&with_links(
        "(from: (0, 9), to: (1, 0)), (from: (1, 0), to: (0, 9))",
    ));
    assert!(
        message.contains("links[1]: joins the same two particles as an earlier link"),
        "{message}"
    );
}

#[test]
fn syntax_errors_and_unknown_fields_name_the_place() {
    let message = rejected(&GOOD.replace("substeps: 10", "substeps: 10, speed: 3"));
    assert!(message.contains("line 4"), "{message}");
    let message = rejected(&GOOD.replace(
        "duration: 1.0,",
        "duration: 1.0,\n    constraints: (solver: \"magic\"),",
    ));
    assert!(
        message.contains("line 4") && message.contains("valid solvers"),
        "{message}"
    );
}

#[test]
fn unknown_scenarios_and_bad_overrides_are_refused() {
    let options = RunOptions {
        scenario: "no_such_scene".into(),
        ..Default::default()
    };
    match load_scenario(&options) {
        Err(RunError::UnknownScenario { valid, .. }) => assert!(valid.contains("long_strand")),
        other => panic!("{other:?}"),
    }
    let options = RunOptions {
        scenario: "long_strand".into(),
        dt: Some(-1.0),
        ..Default::default()
    };
    let message = load_scenario(&options).unwrap_err().to_string();
    assert!(message.contains("command line: step.dt"), "{message}");
}

#[test]
fn a_missing_file_is_reported_by_name() {
    let options = RunOptions {
        scenario: "x".into(),
        scene_file: Some("does/not/exist.ron".into()),
        ..Default::default()
    };
    let message = load_scenario(&options).unwrap_err().to_string();
    assert!(
        message.starts_with("does/not/exist.ron: file:"),
        "{message}"
    );
}

#[test]
fn a_step_longer_than_the_run_is_rejected() {
    let message = rejected(&GOOD.replace("dt: 0.001", "dt: 2.0"));
    assert!(
        message.contains("step.dt: 2e0 s is longer than the run (1e0 s)"),
        "{message}"
    );
}

#[test]
fn a_state_gone_non_finite_stops_the_run_with_an_error() {
    // Steps of 1e300 s: the first overflows the velocities, the next the positions.
    let scene = GOOD
        .replace("duration: 1.0", "duration: 4e300")
        .replace("dt: 0.001, substeps: 10", "dt: 1e300, substeps: 1");
    let options = RunOptions {
        scene_file: Some(scene_file("huge_step.ron", &scene)),
        check_crossings: true,
        ..Default::default()
    };
    match bevy_strands_app::runner::run(&options, |_| {}) {
        Err(RunError::NonFinite { step, what, .. }) => {
            assert!(step <= 4, "found late: step {step}");
            assert!(what.contains("strand 0, particle 0"), "{what}");
        }
        other => panic!("a non-finite state was not refused: {other:?}"),
    }
}

#[test]
fn a_gravity_no_step_can_resolve_ends_in_the_fail_safe_and_says_so() {
    // long_strand under a gravity of 1e308 (its particles weigh 1 kg: the forces stay
    // finite): the impulses cannot stop the strand at the floor, the rigid impact
    // zones do, every step. Exact and uncrossed, but not physics: the report says so.
    let scene = include_str!("../../assets/scenes/long_strand.ron")
        .replace("gravity: (0.0, -9.81)", "gravity: (0.0, -1e308)");
    let options = RunOptions {
        scene_file: Some(scene_file("heavy.ron", &scene)),
        seconds: Some(0.3),
        check_crossings: true,
        ..Default::default()
    };
    let report = bevy_strands_app::runner::run(&options, |_| {}).unwrap();
    assert_eq!(report.edge_crossings, Some(0));
    assert!(report.max_rel_length_error < 1e-9);
    assert_eq!(report.failsafe_steps, report.steps);
    assert!(
        report
            .notes
            .iter()
            .any(|n| n.contains("90 of 90 steps ended in the collision fail-safe")),
        "{:?}",
        report.notes
    );
}

#[test]
fn a_scene_larger_than_its_particle_cap_is_refused_before_anything_is_allocated() {
    let message = rejected(&GOOD.replace("particles: 10,", "particles: 1000000000,"));
    assert!(
        message.contains(
            "max_particles: the scene starts with 1000000004 particles, more than 4000000"
        ),
        "{message}"
    );
    // The cap is the scene's: lowered, the good scene's 14 particles are too many.
    let lowered = GOOD.replace("duration: 1.0,", "duration: 1.0, max_particles: 13,");
    assert!(rejected(&lowered).contains("starts with 14 particles, more than 13"));
    let raised = GOOD.replace("duration: 1.0,", "duration: 1.0, max_particles: 14,");
    assert!(Scenario::parse(&raised, "ok.ron").is_ok());
}

/// The problem `headless_app` finds with the initial state of a scene that parses.
fn refused_at_start(text: &str) -> String {
    let scene = Scenario::parse(text, "start.ron").expect("the scene parses");
    match headless_app(&scene) {
        Ok(_) => panic!("the initial state was accepted:\n{text}"),
        Err(RunError::Scenario(e)) => {
            assert_eq!(
                (e.file.as_str(), e.item.as_str()),
                ("start.ron", "initial state")
            );
            e.problem
        }
        Err(e) => panic!("refused for another reason: {e}"),
    }
}

#[test]
fn an_initial_state_that_crosses_overlaps_or_leaves_the_container_is_refused() {
    assert!(headless_app(&Scenario::parse(GOOD, "good.ron").unwrap()).is_ok());
    let with_strand = |shape: &str| {
        GOOD.replace(
            "mass: 2.0),",
            &format!("mass: 2.0),\n        (shape: {shape}),"),
        )
    };
    // A vertical strand through strand 0 (y = 0.5, x from 0.1 to 0.55).
    let crossing = with_strand("Polyline(points: [(0.32, 0.4), (0.32, 0.6)])");
    let problem = refused_at_start(&crossing);
    assert!(
        problem.starts_with(
            "the edge from strands[2] particle 0 to strands[2] particle 1 crosses the edge \
             from strands[0] particle 4 to strands[0] particle 5 (pairs of edges crossing \
             at the start: 1)"
        ),
        "{problem}"
    );
    // A particle 1e-3 above strand 0, inside its cushion.
    let close = with_strand("Polyline(points: [(0.33, 0.501), (0.33, 0.6)])");
    let problem = refused_at_start(&close);
    assert!(
        problem.starts_with("strands[2] particle 0 is 1.0000000000000009e-3 from the edge from strands[0] particle 4")
            && problem.contains("closer than the thickness 4e-3"),
        "{problem}"
    );
    // Pinned on the floor: nothing pushes it off, but it touches a wall edge.
    let on_wall = with_strand("Polyline(points: [(0.7, 0.0), (0.7, 0.1)]), pinned: [0]");
    let problem = refused_at_start(&on_wall);
    assert!(problem.contains("the container particle"), "{problem}");
    assert!(
        problem.starts_with("the edge from strands[2] particle 0 to strands[2] particle 1 crosses"),
        "{problem}"
    );
    // Entirely outside the box.
    let outside = with_strand("Polyline(points: [(1.5, 0.5), (1.6, 0.5)])");
    let problem = refused_at_start(&outside);
    assert!(
        problem.starts_with("strands[2] particle 0 at DVec2(1.5, 0.5) is not inside the container"),
        "{problem}"
    );
    // Allowed, with a reason; a reason may not be empty.
    let allowed = crossing.replace(
        "duration: 1.0,",
        "duration: 1.0, allow_initial_contact: Some(\"testing a crossed start\"),",
    );
    assert!(headless_app(&Scenario::parse(&allowed, "ok.ron").unwrap()).is_ok());
    let message = rejected(&crossing.replace(
        "duration: 1.0,",
        "duration: 1.0, allow_initial_contact: Some(\" \"),",
    ));
    assert!(
        message.contains("allow_initial_contact: give the reason"),
        "{message}"
    );
}

#[test]
fn a_drain_that_would_keep_less_than_a_strand_is_refused() {
    let with_drain = |n: usize| {
        GOOD.replace(
            "duration: 1.0,",
            &format!("duration: 1.0, drain: Some((max_particles: {n})),"),
        )
    };
    let message = rejected(&with_drain(1));
    assert!(
        message.contains("drain.max_particles") && message.contains("at least 2"),
        "{message}"
    );
    assert!(Scenario::parse(&with_drain(2), "ok.ron").is_ok());
}
