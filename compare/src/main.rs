//! bevy_strands beside the rigid-body engines a Bevy user would pick instead, in one
//! run.
//!
//! `cargo run --release -p bevy_strands_compare -- [pile|long_strand] [SECONDS]`
//! (both by default; `pile` for its scene's 2 s, `long_strand` for 10 s).
//!
//! `pile`: the built-in `pile` (200 strands of 15 particles, 3 000 particles, dropped
//! at once) at 1/300 s with the crossing check on, then the same strands as chains of
//! capsule links (radius half the strands' thickness, friction 0.3, each strand's
//! mass shared among its links) in rapier2d (revolute impulse joints) and in avian2d
//! (distance joints of rest length zero at the link ends), each at 1/60 s and 1/300 s.
//! `long_strand`: the built-in scene beside the same rope in Rapier.
//!
//! For each run it prints the real-time factor (the engine's steps only; ours includes
//! its crossing check), the largest stretch (an edge's relative length error for the
//! strands; the gap between two joined link ends over the link length for the
//! chains), the steps that end with two links crossing, and links that left the box.

mod avian_world;
mod chain;
mod rapier_world;
mod report;

use bevy_strands_app::report::Report;
use bevy_strands_app::runner::{RunOptions, load_scenario, run};

use chain::Chains;
use report::EngineRun;

fn main() {
    let mut args = std::env::args().skip(1);
    let (scene, seconds) = match (args.next(), args.next()) {
        (None, _) => (None, None),
        (Some(scene), seconds) => (Some(scene), seconds),
    };
    let seconds: Option<f64> = match seconds.map(|a| a.parse::<f64>()) {
        None => None,
        Some(Ok(s)) if s > 0.0 && s.is_finite() => Some(s),
        Some(_) => usage(),
    };
    match scene.as_deref() {
        None => {
            pile(seconds);
            long_strand(seconds);
        }
        Some("pile") => pile(seconds),
        Some("long_strand") => long_strand(seconds),
        Some(_) => usage(),
    }
}

fn usage() -> ! {
    eprintln!("usage: bevy_strands_compare [pile|long_strand] [SECONDS > 0]");
    std::process::exit(2);
}

fn ours(
    scene: &str,
    seconds: Option<f64>,
    dt: Option<f64>,
    threads: Option<usize>,
    check: bool,
) -> (f64, Report) {
    let options = RunOptions {
        scenario: scene.into(),
        seconds,
        dt,
        threads,
        check_crossings: check,
        ..Default::default()
    };
    match run(&options, |_| {}) {
        Ok(report) => (report.sim_time / report.steps as f64, report),
        Err(error) => {
            eprintln!("{scene}: {error}");
            std::process::exit(1);
        }
    }
}

/// One line of the table: engine, model, length unit, step, threads, steps, wall
/// seconds, real-time factor, stretch, crossed steps, most crossed pairs, escaped.
fn line(cells: [String; 12]) {
    let [
        engine,
        model,
        unit,
        step,
        threads,
        steps,
        wall,
        rtf,
        stretch,
        crossed,
        pairs,
        escaped,
    ] = cells;
    println!(
        "{engine:<12} {model:<40} {unit:>5} {step:>6} {threads:>7} {steps:>6} {wall:>8} \
         {rtf:>9} {stretch:>9} {crossed:>7} {pairs:>5} {escaped:>7}"
    );
}

fn header() {
    line(
        [
            "engine",
            "model",
            "unit",
            "step",
            "threads",
            "steps",
            "wall s",
            "real-time",
            "stretch",
            "crossed",
            "pairs",
            "escaped",
        ]
        .map(String::from),
    );
}

fn step_name(dt: f64) -> String {
    format!("1/{}", (1.0 / dt).round())
}

fn row(run: &EngineRun, dt: f64) {
    line([
        run.engine.into(),
        run.model.into(),
        run.length_unit.to_string(),
        step_name(dt),
        run.threads.to_string(),
        run.steps.to_string(),
        format!("{:.3}", run.wall),
        format!("{:.3}", run.real_time_factor(dt)),
        format!("{:.2e}", run.stretch),
        run.crossed_steps.to_string(),
        run.most_crossed_pairs.to_string(),
        run.escaped.to_string(),
    ]);
}

/// Our line: the edges' largest relative length error as the stretch, and the step
/// ends with crossed edges (`-` when not checked).
fn our_row(model: &str, dt: f64, report: &Report) {
    line([
        "bevy_strands".into(),
        model.into(),
        "-".into(),
        step_name(dt),
        report.threads.to_string(),
        report.steps.to_string(),
        format!("{:.3}", report.wall_seconds),
        format!("{:.3}", report.real_time_factor),
        format!("{:.2e}", report.max_rel_length_error),
        report.edge_crossings.map_or("-".into(), |c| c.to_string()),
        "-".into(),
        "-".into(),
    ]);
}

fn pile(seconds: Option<f64>) {
    let options = RunOptions {
        scenario: "pile".into(),
        ..Default::default()
    };
    let scenario = load_scenario(&options).expect("the built-in pile");
    let scale = scenario.scale.expect("the pile is a scaled scene");
    let seconds = seconds.unwrap_or(scenario.duration);
    let chains = Chains::from_scale(
        &scale,
        scenario.collisions.thickness,
        scenario.collisions.friction,
        1.0,
    );
    println!(
        "pile: {} chains, {} links, {} link ends; {seconds} s simulated",
        chains.strands.len(),
        chains.links(),
        chains.particles()
    );
    header();
    // Ours at its default step, then at a game's fixed step (one step per tick).
    for step in [None, Some(1.0 / 60.0)] {
        let (dt, report) = ours("pile", Some(seconds), step, None, true);
        our_row("exact edges, contact Newton / sweeps", dt, &report);
    }
    // Each engine at its default length unit (1 m) and at the links' own scale, which
    // their guides ask for when objects are far from a metre.
    let link = 0.02;
    for dt in [1.0 / 60.0, 1.0 / 300.0] {
        let steps = (seconds / dt).round() as u64;
        for unit in [1.0, link] {
            row(&rapier_world::run(&chains, dt as f32, steps, unit), dt);
            row(&avian_world::run(&chains, dt as f32, steps, unit), dt);
        }
    }
}

fn long_strand(seconds: Option<f64>) {
    let (dt, report) = ours("long_strand", seconds.or(Some(10.0)), None, Some(1), false);
    // The same rope: 59 links of 15 mm, tilted 75° with its lower end at
    // (0.35, 0.10), in the unit box, each link end 1/60 kg as the strand's particles.
    let angle = 75f64.to_radians();
    let strand = (0..60)
        .map(|k| {
            let s = 0.015 * k as f64;
            [
                (0.35 + s * angle.cos()) as f32,
                (0.102 + s * angle.sin()) as f32,
            ]
        })
        .collect();
    let chains = Chains {
        strands: vec![strand],
        container: ([0.0, 0.0], [1.0, 1.0]),
        radius: 0.002,
        friction: 0.3,
        link_mass: 1.0 / 60.0,
    };
    println!(
        "long_strand: one rope of 60 particles; {} s simulated",
        report.sim_time
    );
    header();
    our_row("exact edges (crossing check off)", dt, &report);
    row(
        &rapier_world::run(&chains, dt as f32, report.steps, 1.0),
        dt,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pile's first row only: three chains falling onto the floor, nothing on top.
    fn one_row() -> (Chains, f64) {
        let options = RunOptions {
            scenario: "pile".into(),
            ..Default::default()
        };
        let scenario = load_scenario(&options).unwrap();
        let mut scale = scenario.scale.unwrap();
        scale.strands = 3;
        let chains = Chains::from_scale(&scale, 0.004, 0.3, 1.0);
        (chains, 0.5)
    }

    #[test]
    fn a_row_of_chains_lands_whole_in_both_engines() {
        let (chains, seconds) = one_row();
        for unit in [1.0, 0.02] {
            let dt = 1.0 / 300.0;
            let steps = (seconds / dt) as u64;
            for run in [
                rapier_world::run(&chains, dt as f32, steps, unit),
                avian_world::run(&chains, dt as f32, steps, unit),
            ] {
                // The harness, not the engines, is on trial: joints hold a light
                // load, links stay apart and in the box.
                let what = format!("{} at length unit {unit}", run.engine);
                assert!(run.stretch < 0.1, "{what}: stretch {}", run.stretch);
                assert_eq!(run.crossed_steps, 0, "{what}: crossed steps");
                assert_eq!(run.escaped, 0, "{what}: links out of the box");
                assert_eq!(run.steps, steps);
            }
        }
    }
}
