//! Every canonical scenario through the runner: short runs with their expected counts
//! and no crossings, pictures that decode to what was asked, and bad command lines
//! refused with a message.

use std::path::PathBuf;
use std::process::Command;

use bevy_strands_app::export::FrameSettings;
use bevy_strands_app::report::Report;
use bevy_strands_app::runner::{RunOptions, run};

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

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bevy_strands_tests_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn long_strand_runs_with_its_counts() {
    let report = run_ok(&options("long_strand", 0.3));
    assert_eq!(
        (report.particles, report.strands, report.constrained_edges),
        (64, 2, 59)
    );
    assert_eq!(report.edge_crossings, Some(0));
    assert!(report.max_rel_length_error < 1e-12);
    assert_eq!(report.steps, 90); // 0.3 s at the default 1/300
}

#[test]
fn long_strand_stays_exact_through_contact_at_larger_steps() {
    // At dt = 1/300 the strand lands moving a third of an edge per step, so the contact
    // re-projection must take corrections of that size; at 1/120 and 1/90, most of an
    // edge, and re-projections and collisions alternate several times before they
    // agree. At 1/90 a particle once crept through the floor below the speed the
    // detection counted as approaching.
    for steps_per_second in [300.0, 120.0, 90.0] {
        let report = run_ok(&RunOptions {
            dt: Some(1.0 / steps_per_second),
            substeps: Some(3),
            ..options("long_strand", 3.0)
        });
        assert_eq!(report.edge_crossings, Some(0), "dt 1/{steps_per_second}");
        assert!(
            report.max_rel_length_error < 1e-9,
            "dt 1/{steps_per_second}: {:e}",
            report.max_rel_length_error
        );
    }
}

#[test]
fn the_factories_stay_exact_and_uncrossed_at_game_sized_steps() {
    // Five seconds at 1/600 and 1/300: the strands pile up on the floor and on each
    // other, held by the contact solve, with continuous detection verifying every
    // step.
    for (scenario, steps_per_second) in [
        ("spaghetti_factory", 600.0),
        ("spaghetti_factory", 300.0),
        ("meatball_factory", 600.0),
    ] {
        let report = run_ok(&RunOptions {
            dt: Some(1.0 / steps_per_second),
            substeps: Some(3),
            ..options(scenario, 5.0)
        });
        let name = format!("{scenario} at 1/{steps_per_second}");
        assert_eq!(
            report.edge_crossings,
            Some(0),
            "{name}: {:?}",
            report.first_crossing
        );
        assert!(
            report.max_rel_length_error < 1e-9,
            "{name}: {:e}",
            report.max_rel_length_error
        );
        assert!(
            report.contacts > 0 && report.contact_projection_solves > 0,
            "{name}"
        );
    }
}

#[test]
fn the_dense_pile_lands_at_its_default_step_uncrossed_and_exact() {
    // 3 000 particles dropped at once at 1/300 s: they fall for a third of a second
    // and land on the floor and on each other, row upon row, within the next half.
    let report = run_ok(&options("pile", 0.8));
    assert_eq!(report.steps, 240);
    assert_eq!(
        report.edge_crossings,
        Some(0),
        "{:?}",
        report.first_crossing
    );
    assert!(
        report.max_rel_length_error < 1e-9,
        "{:e}",
        report.max_rel_length_error
    );
    // Held by the contact solve: thousands of contacts a step, the fail-safe never.
    assert!(report.contacts > 240 * 1000, "{}", report.contacts);
    assert_eq!(report.failsafe_steps, 0);
}

#[test]
fn the_coiling_rope_is_solved_by_the_contact_newton_uncrossed_and_exact() {
    // A 1 000-particle rope dropped in rows: by 0.7 s its lower rows have landed on the
    // floor and the next ones on them. Its rows touch one strand as long as the rope,
    // so the contact projections go to the contact Newton, not to the sweeps.
    let report = run_ok(&options("rope_coil", 0.7));
    assert_eq!(
        report.edge_crossings,
        Some(0),
        "{:?}",
        report.first_crossing
    );
    assert!(
        report.max_rel_length_error < 1e-9,
        "{:e}",
        report.max_rel_length_error
    );
    assert!(report.contacts > 10_000, "{}", report.contacts);
    assert!(
        report.contact_projection_newton_solves == report.contact_projection_solves
            && report.contact_projection_factorizations >= report.contact_projection_solves,
        "{} of {} by Newton, {} factorizations",
        report.contact_projection_newton_solves,
        report.contact_projection_solves,
        report.contact_projection_factorizations
    );
    assert_eq!(report.failsafe_steps, 0);
}

#[test]
fn branches_solves_its_trees_and_graphs_exactly() {
    // One second: the ladder is thrown into the trees and falls back on the truss.
    let report = run_ok(&options("branches", 1.0));
    // The box; three trees of 14 + 6 + 5 particles joined by two links each; the
    // ladder's two rails of 10 and four rungs; the truss' two chords of 6 and eleven
    // braces. Every link is a strand of one edge.
    assert_eq!(
        (report.particles, report.strands, report.constrained_edges),
        (
            4 + 3 * 25 + 20 + 12,
            1 + 3 * (3 + 2) + (2 + 4) + (2 + 11),
            3 * (13 + 5 + 4 + 2) + (9 + 9 + 4) + (5 + 5 + 11)
        )
    );
    assert_eq!(
        (
            report.islands.tree,
            report.islands.graph,
            report.islands.unsolved
        ),
        (3, 2, 0)
    );
    assert_eq!(report.edge_crossings, Some(0));
    assert!(report.contacts > 0);
    assert!(
        report.max_rel_length_error < 1e-12,
        "{:e}",
        report.max_rel_length_error
    );
}

#[test]
fn spaghetti_factory_emits_on_schedule() {
    // Emissions at t = 0, 0.05, …, 0.65: fourteen particles, a finished strand of 13
    // and one particle of the next.
    let report = run_ok(&options("spaghetti_factory", 0.66));
    assert_eq!(report.particles, 4 + 14);
    assert_eq!(report.strands, 2, "walls and one finished strand");
    assert_eq!(report.constrained_edges, 12);
    assert_eq!(report.edge_crossings, Some(0));
    assert!(report.max_rel_length_error < 1e-12);
}

#[test]
fn a_drain_keeps_the_factory_pile_bounded_exact_and_uncrossed() {
    // 6 s of extrusion make 120 particles; the drain keeps 40 (walls left out), plus
    // the strand being extruded, which is held and never leaves.
    let text = include_str!("../../assets/scenes/spaghetti_factory.ron");
    let end = text.rfind(')').unwrap();
    let scene = scratch("drained_factory.ron");
    let drained = format!("{}    drain: Some((max_particles: 40)),\n)\n", &text[..end]);
    std::fs::write(&scene, drained).unwrap();
    let report = run_ok(&RunOptions {
        scene_file: Some(scene),
        ..options("", 6.0)
    });
    let walls = 4;
    assert!(
        report.particles - walls <= 40 + 13,
        "{} particles",
        report.particles
    );
    let note = report
        .notes
        .iter()
        .find(|n| n.starts_with("the drain took out"))
        .unwrap_or_else(|| panic!("no drain note: {:?}", report.notes));
    // Whole strands of 13 leave, the lowest first: about (120 - 40) / 13 of them.
    let taken: usize = note["the drain took out ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((5..=8).contains(&taken), "{note}");
    assert!(
        note.contains(&format!("({} particles)", 13 * taken)),
        "{note}"
    );
    assert_eq!(report.edge_crossings, Some(0));
    assert!(
        report.max_rel_length_error < 1e-12,
        "{:e}",
        report.max_rel_length_error
    );
}

#[test]
fn the_bending_model_is_chosen_from_the_command_line_and_named_in_the_report() {
    let quadratic = run_ok(&RunOptions {
        bending: Some("quadratic".into()),
        ..options("furry_creature_limp", 0.2)
    });
    assert_eq!(quadratic.config["step"]["bending"], "quadratic");
    assert!(quadratic.max_rel_length_error < 1e-12);
    let angle = run_ok(&options("furry_creature_limp", 0.2));
    assert_eq!(angle.config["step"]["bending"], "angle");
    // The same scene moved by another bending model: close, not the same.
    assert!((quadratic.max_speed_at_end - angle.max_speed_at_end).abs() < 0.5);
    assert_ne!(quadratic.max_speed_at_end, angle.max_speed_at_end);
    let refused = run(
        &RunOptions {
            bending: Some("cubic".into()),
            ..options("long_strand", 0.1)
        },
        |_| {},
    );
    let Err(error) = refused else {
        panic!("an unknown bending model was accepted");
    };
    let message = error.to_string();
    assert!(
        message.contains("--bending") && message.contains("angle, angle-explicit, quadratic"),
        "{message}"
    );
}

#[test]
fn meatball_factory_drops_spinning_loops() {
    let report = run_ok(&options("meatball_factory", 2.2));
    // Meatballs at 0.5 s and 2.0 s; spaghetti particles at 0, 0.05, …, 2.15 (one due
    // at 2.2 s would start the tick after the run's end).
    let meatballs = 2;
    let spaghetti_particles = 44;
    assert_eq!(report.particles, 4 + 3 * meatballs + spaghetti_particles);
    assert_eq!(report.edge_crossings, Some(0));
    assert!(
        report.max_rel_length_error < 1e-12,
        "{:e}",
        report.max_rel_length_error
    );
}

#[test]
fn furry_creatures_keep_their_hairs_exact() {
    // The fur that stands out (stiff hair, bent implicitly, at a game's step) and the
    // limp mat.
    for (scenario, bending) in [
        ("furry_creature", "quadratic"),
        ("furry_creature_limp", "angle"),
    ] {
        let report = run_ok(&options(scenario, 0.05));
        assert_eq!(report.config["step"]["bending"], bending, "{scenario}");
        // 400 hairs of 12 and the body's collision outline (a driven wall polygon).
        assert_eq!(report.strands, 401);
        assert!(report.particles > 4800 && report.particles < 4800 + 200);
        // Each hair's first edge is between two driven particles: not constrained.
        assert_eq!(report.constrained_edges, 400 * 10);
        assert!(report.max_rel_length_error < 1e-12, "{scenario}");
        assert_eq!(report.edge_crossings, Some(0), "{scenario}");
        assert!(
            !(report.notes.iter()).any(|n| n.contains("collisions are off")),
            "{:?}",
            report.notes
        );
    }
}

#[test]
fn scale_takes_its_size_from_the_command_line() {
    let mut small = options("scale", 0.05);
    small.strands = Some(10);
    small.particles = Some(20);
    let report = run_ok(&small);
    assert_eq!((report.particles, report.strands), (4 + 200, 11));
    assert_eq!(report.edge_crossings, Some(0));
    small.no_collisions = true;
    let report = run_ok(&small);
    assert_eq!((report.contacts, report.collisions), (0, 0));
    assert!(report.particle_steps_per_second > 0.0);
}

#[test]
fn gif_png_frames_and_plot_decode_to_what_was_asked() {
    let (gif_path, frames, plot) = (scratch("run.gif"), scratch("frames"), scratch("plot.png"));
    let mut options = options("long_strand", 0.5);
    options.gif = Some(gif_path.clone());
    options.frames = Some(frames.clone());
    options.plot = Some(plot.clone());
    options.frame_settings = FrameSettings {
        fps: 10.0,
        width: 200,
        height: 120,
    };
    let report = run_ok(&options);
    assert_eq!(report.pictures.len(), 3, "{:?}", report.pictures);

    // 0.5 s at 10 frames per second: frames at 0.01, 0.1, 0.2, 0.3, 0.4, 0.5.
    let decoder = gif::DecodeOptions::new();
    let mut reader = decoder
        .read_info(std::fs::File::open(&gif_path).unwrap())
        .unwrap();
    assert_eq!((reader.width(), reader.height()), (200, 120));
    let mut count = 0;
    while reader.read_next_frame().unwrap().is_some() {
        count += 1;
    }
    assert_eq!(count, 6);

    let mut pngs: Vec<_> = std::fs::read_dir(&frames)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    pngs.sort();
    assert_eq!(pngs.len(), 6);
    for png_path in &pngs {
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(png_path).unwrap(),
        ));
        let reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (200, 120));
    }

    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&plot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    assert_eq!((reader.info().width, reader.info().height), (900, 500));
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut pixels).unwrap();
    // Not blank: the white background holds coloured curves.
    assert!(pixels.chunks(3).any(|p| p[0] != p[1] || p[1] != p[2]));
}

fn strands_command(args: &[&str]) -> (bool, String, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_strands"))
        .args(args)
        .output()
        .expect("the runner starts");
    (
        output.status.success(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn bad_command_lines_are_refused_with_a_message() {
    let (ok, _, err) = strands_command(&["run", "lasagne"]);
    assert!(
        !ok && err.contains("unknown scenario 'lasagne'") && err.contains("long_strand"),
        "{err}"
    );
    let (ok, _, err) = strands_command(&["run", "long_strand", "--speed", "3"]);
    assert!(!ok && err.contains("--speed"), "{err}");
    let (ok, _, err) = strands_command(&["run", "long_strand", "--size", "big"]);
    assert!(!ok && err.contains("not a size like 512x512"), "{err}");
    let (ok, _, err) = strands_command(&["run", "long_strand", "--strands", "5"]);
    assert!(!ok && err.contains("only the scale scenario"), "{err}");
    let (ok, _, err) = strands_command(&["run", "long_strand", "--gif", "x.gif", "--fps", "0"]);
    assert!(!ok && err.contains("--fps 0"), "{err}");
    let (ok, _, err) = strands_command(&["run", "long_strand", "--solver", "magic"]);
    assert!(
        !ok && err.contains("valid solvers: tridiagonal, gauss-seidel, jacobi, springs"),
        "{err}"
    );
}

#[test]
fn list_and_json_output() {
    let (ok, out, _) = strands_command(&["list"]);
    assert!(ok);
    for name in [
        "long_strand",
        "spaghetti_factory",
        "meatball_factory",
        "furry_creature",
        "furry_creature_limp",
        "branches",
        "scale",
    ] {
        assert!(out.contains(name), "{out}");
    }
    let (ok, out, _) = strands_command(&["run", "long_strand", "--seconds", "0.05", "--json"]);
    assert!(ok);
    let report: serde_json::Value = serde_json::from_str(&out).expect("stdout is one JSON object");
    assert_eq!(report["scenario"], "long_strand");
    assert_eq!(report["edge_crossings"], 0);
    let (_, out, _) = strands_command(&[
        "run",
        "long_strand",
        "--seconds",
        "0.05",
        "--json",
        "--no-check",
    ]);
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(report["edge_crossings"].is_null());
    let (ok, out, _) = strands_command(&["run", "--help"]);
    assert!(ok && out.contains("--gif") && out.contains("--plot") && out.contains("--no-check"));
}

#[test]
fn a_blocked_inlet_stops_the_factory_instead_of_pushing_through() {
    // A strand pulled taut between two pins lies across the extrusion's path: nothing
    // can move it out of the way of the pinned, driven particles at the inlet.
    let scene = r#"(
        name: "blocked_inlet",
        duration: 1.0,
        step: (gravity: (0.0, 0.0)),
        container: Some((min: (0.0, 0.0), max: (1.0, 1.0))),
        strands: [(
            shape: Line(start: (0.9, 0.45), angle_degrees: 90.0, particles: 6, spacing: 0.02),
            pinned: [0, 5],
        )],
        spaghetti_factory: Some((
            inlet: (0.99, 0.5),
            velocity: (-1.0, 0.0),
            interval: 0.05,
            particles_per_strand: 13,
        )),
    )"#;
    the_inlet_waits_and_nothing_crosses("blocked_inlet", scene, 1.0);
}

#[test]
fn no_edge_is_born_across_a_strand_that_moves_with_the_extrusion() {
    // A free strand crossing the extrusion's path upstream of the inlet, moving at the
    // extrusion's speed: it keeps ahead of the held particles, so it never blocks the
    // stretch they sweep, but it passes the inlet between two emissions and would lie
    // across the next edge when it is born.
    let scene = r#"(
        name: "edge_born_across",
        duration: 0.3,
        step: (gravity: (0.0, 0.0)),
        strands: [(
            shape: Line(start: (1.01, 0.45), angle_degrees: 90.0, particles: 6, spacing: 0.02),
            velocity: (-1.0, 0.0),
        )],
        spaghetti_factory: Some((
            inlet: (0.99, 0.5),
            velocity: (-1.0, 0.0),
            interval: 0.05,
            particles_per_strand: 13,
        )),
    )"#;
    the_inlet_waits_and_nothing_crosses("edge_born_across", scene, 0.3);
}

/// Run the factory scene `scene` for `seconds`: its inlet must have stood still at
/// some point, with no crossing and exact edges.
fn the_inlet_waits_and_nothing_crosses(name: &str, scene: &str, seconds: f64) {
    let file = scratch(&format!("{name}.ron"));
    std::fs::write(&file, scene).unwrap();
    let report = run_ok(&RunOptions {
        scene_file: Some(file),
        ..options(name, seconds)
    });
    assert_eq!(
        report.edge_crossings,
        Some(0),
        "{name}: {:?}",
        report.first_crossing
    );
    assert!(
        report.notes.iter().any(|n| n.contains("inlet was blocked")),
        "{name}: {:?}",
        report.notes
    );
    assert!(
        report.max_rel_length_error < 1e-9,
        "{name}: {:e}",
        report.max_rel_length_error
    );
}
