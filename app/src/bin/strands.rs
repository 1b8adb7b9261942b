//! `strands`: run a canonical scenario headless and print its report.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use bevy_strands::constraints::SolverKind;
use bevy_strands_app::builtin::BUILTIN_SCENES;
use bevy_strands_app::export::FrameSettings;
use bevy_strands_app::runner::{RunOptions, run};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

#[derive(Parser)]
#[command(
    name = "strands",
    version,
    about = "Run bevy_strands scenarios headless"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenarios.
    List,
    /// Run a scenario and print its report.
    Run(Box<RunArgs>),
}

#[derive(clap::Args)]
struct RunArgs {
    /// Scenario name (see `strands list`); not needed with --scene or --from.
    #[arg(required_unless_present_any = ["scene", "from"])]
    scenario: Option<String>,
    /// Run this scene file instead of the built-in scenario.
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// Simulated seconds (default: the scene's duration).
    #[arg(long, value_name = "S")]
    seconds: Option<f64>,
    /// Step size in seconds (default: the scene's, 1/300 for the built-in scenes).
    #[arg(long, value_name = "DT")]
    dt: Option<f64>,
    /// Steps per tick (default: the scene's).
    #[arg(long, value_name = "N")]
    substeps: Option<u32>,
    /// Threads a stage may use (default 0: one per core). The report is the same bit
    /// for bit whatever the count.
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Constraint solver.
    #[arg(long, value_name = "NAME", long_help = solver_help())]
    solver: Option<String>,
    /// Contact solver (default: the scene's, `auto`): `auto` (per contact group, the
    /// sweeps on short strands and Newton on long ones), `newton` (rows and edges
    /// together, one sparse factorization a Newton step) or `gauss-seidel` (sweeps over
    /// each row's response on its whole strands, the earlier design).
    #[arg(long, value_name = "NAME")]
    contact_solver: Option<String>,
    /// Bending model (default: the scene's): `angle` (turning angle; implicit on strands
    /// too stiff for the step, explicit on the others), `angle-explicit` (always
    /// explicit, for studies) or `quadratic` (isometric quadratic, implicit).
    #[arg(long, value_name = "MODEL")]
    bending: Option<String>,
    /// Cap on constraint-projection iterations (relaxation sweeps for the baselines) per
    /// island per step (default: the scene's, 20).
    #[arg(long, value_name = "N")]
    iterations: Option<u32>,
    /// A step that would end in the collision fail-safe is taken again as two halves,
    /// down to dt / 2^N (default: the scene's, 2; 0: never).
    #[arg(long, value_name = "N")]
    step_halvings: Option<u32>,
    /// A step that follows a hard one (collision impulses, a capped contact solve, a
    /// halving) is taken in parts from the start, down to dt / 2^N; eight easy steps
    /// grow the parts back a level (default: the scene's, 2; 0: never).
    #[arg(long, value_name = "N")]
    split_ahead: Option<u32>,
    /// Keep stretch springs on constrained edges too (constraint-drift studies).
    #[arg(long)]
    stretch_springs: bool,
    /// Never put strands at rest to sleep (by default a group that stays within 2 cm
    /// of one place for a second sleeps).
    #[arg(long)]
    no_sleep: bool,
    /// Take the constraint direction at the start of the step (torque-free impulses)
    /// instead of at the end (fast projection).
    #[arg(long)]
    start_of_step: bool,
    /// Print the report as one JSON object alone on stdout.
    #[arg(long)]
    json: bool,
    /// Do not count edge crossings (the report then says null, not 0).
    #[arg(long)]
    no_check: bool,
    /// Turn collisions off.
    #[arg(long)]
    no_collisions: bool,
    /// Strands of the scale scenario.
    #[arg(long, value_name = "S")]
    strands: Option<usize>,
    /// Particles per strand of the scale scenario.
    #[arg(long, value_name = "P")]
    particles: Option<usize>,
    /// Write an animated GIF of the run.
    #[arg(long, value_name = "FILE")]
    gif: Option<PathBuf>,
    /// Write numbered PNG frames of the run into this directory.
    #[arg(long, value_name = "DIR")]
    frames: Option<PathBuf>,
    /// Frames per simulated second of --gif and --frames.
    #[arg(long, value_name = "N", default_value_t = 30.0)]
    fps: f64,
    /// Frame size of --gif and --frames, in pixels.
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = parse_size)]
    size: (u32, u32),
    /// Write a plot of the largest relative length error over time (PNG).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Write a snapshot at the end of the first tick at or after this simulated time
    /// (with --snapshot).
    #[arg(long, value_name = "T", requires = "snapshot")]
    snapshot_at: Option<f64>,
    /// The snapshot file to write (with --snapshot-at).
    #[arg(long, value_name = "FILE", requires = "snapshot_at")]
    snapshot: Option<PathBuf>,
    /// Continue the run saved in this snapshot; --seconds is then the time to run to.
    #[arg(long, value_name = "FILE")]
    from: Option<PathBuf>,
    /// End the run at the first step that ends with crossed edges.
    #[arg(long)]
    stop_on_crossing: bool,
    /// Report each stage's share of the wall time (the tick's phases and the step's
    /// stages; the simulation computes the same).
    #[arg(long)]
    profile: bool,
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let parse = |part: Option<&str>| part.and_then(|p| p.trim().parse::<u32>().ok());
    let mut parts = text.split(['x', 'X']);
    match (parse(parts.next()), parse(parts.next()), parts.next()) {
        (Some(w), Some(h), None) => Ok((w, h)),
        _ => Err(format!("'{text}' is not a size like 512x512")),
    }
}

fn solver_help() -> String {
    let mut help = String::from("Constraint solver (default: the scene's). One of:");
    for kind in SolverKind::ALL {
        help.push_str(&format!("\n  {:<12} {}", kind.name(), kind.description()));
    }
    help
}

/// Write to stdout; a closed pipe (`strands … | head`) ends the output quietly.
fn emit(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|()| out.flush());
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::List => {
            for scene in BUILTIN_SCENES {
                match scene.scenario() {
                    Ok(s) => emit(&format!("{:<20} {}\n", scene.name, s.description)),
                    Err(e) => emit(&format!("{:<20} (invalid: {e})\n", scene.name)),
                }
            }
            ExitCode::SUCCESS
        }
        Command::Run(args) => {
            let options = RunOptions {
                scenario: args.scenario.unwrap_or_default(),
                scene_file: args.scene,
                seconds: args.seconds,
                dt: args.dt,
                substeps: args.substeps,
                threads: args.threads,
                solver: args.solver,
                bending: args.bending,
                contact_solver: args.contact_solver,
                iterations: args.iterations,
                step_halvings: args.step_halvings,
                split_ahead: args.split_ahead,
                stretch_springs: args.stretch_springs,
                no_sleep: args.no_sleep,
                start_of_step: args.start_of_step,
                check_crossings: !args.no_check,
                no_collisions: args.no_collisions,
                strands: args.strands,
                particles: args.particles,
                gif: args.gif,
                frames: args.frames,
                plot: args.plot,
                snapshot_at: args.snapshot_at,
                snapshot: args.snapshot,
                from: args.from,
                stop_on_crossing: args.stop_on_crossing,
                profile: args.profile,
                frame_settings: FrameSettings {
                    fps: args.fps,
                    width: args.size.0,
                    height: args.size.1,
                },
            };
            // A progress bar on stderr for runs longer than a second; none with --json
            // when stderr is not a terminal.
            let quiet = args.json && !std::io::stderr().is_terminal();
            let started = Instant::now();
            let mut bar: Option<ProgressBar> = None;
            let result = run(&options, |fraction| {
                if quiet {
                    return;
                }
                if bar.is_none() && started.elapsed() > Duration::from_secs(1) {
                    let style = ProgressStyle::with_template(
                        "{elapsed_precise} [{bar:40}] {percent:>3}% eta {eta}",
                    )
                    .expect("a valid template")
                    .progress_chars("=> ");
                    bar = Some(ProgressBar::new(1000).with_style(style));
                }
                if let Some(bar) = &bar {
                    bar.set_position((fraction * 1000.0) as u64);
                }
            });
            if let Some(bar) = bar {
                bar.finish_and_clear();
            }
            match result {
                Ok(report) if args.json => {
                    emit(&format!("{}\n", report.to_json()));
                    ExitCode::SUCCESS
                }
                Ok(report) => {
                    emit(&report.to_table());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("strands: {e}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}
