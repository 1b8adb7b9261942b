//! Snapshots: a run continued from a snapshot ends exactly as the run it was taken from,
//! and broken snapshot files are refused with a message naming the file and the problem.

use std::path::PathBuf;

use bevy_strands_app::report::Report;
use bevy_strands_app::runner::{RunOptions, run};
use bevy_strands_app::snapshot::RunSnapshot;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bevy_strands_snapshots_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn options(scenario: &str, seconds: f64) -> RunOptions {
    RunOptions {
        scenario: scenario.into(),
        seconds: Some(seconds),
        check_crossings: true,
        ..Default::default()
    }
}

fn run_ok(options: &RunOptions) -> Report {
    run(options, |_| {}).unwrap_or_else(|e| panic!("{}: {e}", options.scenario))
}

/// Every figure of the report but the cost, the notes and the energy account's start
/// (a continued run's account starts at the snapshot; its end is the same).
fn figures(report: &Report) -> serde_json::Value {
    let mut value = serde_json::to_value(report).unwrap();
    let object = value.as_object_mut().unwrap();
    for key in Report::WALL_CLOCK_FIELDS.into_iter().chain([
        "notes",
        "config",
        "energy_start",
        "driven_ticks",
    ]) {
        object.remove(key);
    }
    value
}

#[test]
fn a_run_continued_from_a_snapshot_ends_as_the_uninterrupted_run() {
    // The factories' progress (a strand half extruded at 0.8 s, a meatball dropped at
    // 0.5 s and the next due at 2.0 s) and the creature's roots go through the file.
    for (scenario, at, end) in [
        ("spaghetti_factory", 0.8, 1.5),
        ("meatball_factory", 1.0, 2.2),
        ("furry_creature_limp", 0.02, 0.05),
    ] {
        let whole = run_ok(&options(scenario, end));
        let file = scratch(&format!("{scenario}.ron"));
        let first = run_ok(&RunOptions {
            snapshot_at: Some(at),
            snapshot: Some(file.clone()),
            ..options(scenario, at)
        });
        assert!(
            first.notes.iter().any(|n| n.contains("snapshot written")),
            "{:?}",
            first.notes
        );
        let rest = run_ok(&RunOptions {
            from: Some(file.clone()),
            ..options("", end)
        });
        assert_eq!(figures(&rest), figures(&whole), "{scenario}");
        assert!(
            rest.notes[0].starts_with("continued from"),
            "{:?}",
            rest.notes
        );
        // The file reads back as what was written.
        let snapshot = RunSnapshot::load(&file).unwrap();
        let again = scratch(&format!("{scenario}_again.ron"));
        snapshot.save(&again).unwrap();
        assert_eq!(RunSnapshot::load(&again).unwrap(), snapshot);
    }
}

#[test]
fn a_run_continued_after_despawns_ends_as_the_uninterrupted_run() {
    // A drain keeping 30 particles takes strands out from the second second on: the world that wrote
    // the snapshot hands their freed entity slots to later spawns, the restored one
    // has none to hand out. Strands are solved in the order they arrived, not by
    // entity, so both continue alike.
    let text = include_str!("../../assets/scenes/meatball_factory.ron");
    let end = text.rfind(')').unwrap();
    let scene = scratch("drained.ron");
    std::fs::write(
        &scene,
        format!("{}    drain: Some((max_particles: 30)),\n)\n", &text[..end]),
    )
    .unwrap();
    let scene_options = |seconds| RunOptions {
        scene_file: Some(scene.clone()),
        ..options("", seconds)
    };
    // (Ordered by entity, the continued run met 24 214 contacts to the whole run's
    // 23 822.)
    let whole = run_ok(&scene_options(12.0));
    assert!(
        whole
            .notes
            .iter()
            .any(|n| n.starts_with("the drain took out")),
        "{:?}",
        whole.notes
    );
    let file = scratch("drained_at_5.ron");
    let first = run_ok(&RunOptions {
        snapshot_at: Some(5.0),
        snapshot: Some(file.clone()),
        ..scene_options(5.0)
    });
    assert!(
        first
            .notes
            .iter()
            .any(|n| n.starts_with("the drain took out"))
    );
    let rest = run_ok(&RunOptions {
        from: Some(file),
        ..options("", 12.0)
    });
    assert!(
        rest.notes
            .iter()
            .any(|n| n.starts_with("the drain took out"))
    );
    assert_eq!(figures(&rest), figures(&whole));
}

#[test]
fn broken_snapshots_are_refused_with_the_file_and_the_problem() {
    let missing = run(
        &RunOptions {
            from: Some("no/such/snapshot.ron".into()),
            ..options("", 1.0)
        },
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(missing.starts_with("no/such/snapshot.ron: "), "{missing}");

    let file = scratch("good.ron");
    run_ok(&RunOptions {
        snapshot_at: Some(0.2),
        snapshot: Some(file.clone()),
        ..options("spaghetti_factory", 0.2)
    });
    let text = std::fs::read_to_string(&file).unwrap();
    let broken = scratch("broken.ron");
    std::fs::write(&broken, &text[..text.len() / 2]).unwrap();
    let message = run(
        &RunOptions {
            from: Some(broken.clone()),
            ..options("", 1.0)
        },
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        message.contains("broken.ron: line") && message.contains("column"),
        "{message}"
    );

    // A strand naming a particle the snapshot does not hold.
    let mut snapshot = RunSnapshot::load(&file).unwrap();
    let count = snapshot.state.particles.len() as u32;
    snapshot.state.strands[0].particles[0] = count + 5;
    let inconsistent = scratch("inconsistent.ron");
    snapshot.save(&inconsistent).unwrap();
    let message = run(
        &RunOptions {
            from: Some(inconsistent),
            ..options("", 1.0)
        },
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        message.contains(&format!("names particle {}", count + 5)),
        "{message}"
    );
}

#[test]
fn a_snapshot_needs_both_its_time_and_its_file() {
    let message = run(
        &RunOptions {
            snapshot_at: Some(0.1),
            ..options("long_strand", 0.2)
        },
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(message.contains("give both"), "{message}");
}
