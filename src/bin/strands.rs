//! `strands`: run a canonical scenario headless and print its report.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use bevy_strands::constraints::SolverKind;
use bevy_strands::runner::{RunOptions, run};
use bevy_strands::scenes::BUILTIN_SCENES;
use clap::{Parser, Subcommand};

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
    Run(RunArgs),
}

#[derive(clap::Args)]
struct RunArgs {
    /// Scenario name (see `strands list`).
    scenario: String,
    /// Run this scene file instead of the built-in scenario.
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// Simulated seconds (default: the scene's duration).
    #[arg(long, value_name = "S")]
    seconds: Option<f64>,
    /// Step size in seconds (default: the scene's, 1/3000 for the canonical scenes).
    #[arg(long, value_name = "DT")]
    dt: Option<f64>,
    /// Steps per tick (default: the scene's).
    #[arg(long, value_name = "N")]
    substeps: Option<u32>,
    /// Constraint solver.
    #[arg(long, value_name = "NAME", long_help = solver_help())]
    solver: Option<String>,
    /// Cap on constraint-projection iterations per island per step (default: the
    /// scene's, 20).
    #[arg(long, value_name = "N")]
    iterations: Option<u32>,
    /// Keep stretch springs on constrained edges too (constraint-drift studies).
    #[arg(long)]
    stretch_springs: bool,
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
                match scene.scene() {
                    Ok(s) => emit(&format!("{:<20} {}\n", scene.name, s.description)),
                    Err(e) => emit(&format!("{:<20} (invalid: {e})\n", scene.name)),
                }
            }
            ExitCode::SUCCESS
        }
        Command::Run(args) => {
            let options = RunOptions {
                scenario: args.scenario,
                scene_file: args.scene,
                seconds: args.seconds,
                dt: args.dt,
                substeps: args.substeps,
                solver: args.solver,
                iterations: args.iterations,
                stretch_springs: args.stretch_springs,
                start_of_step: args.start_of_step,
                check_crossings: !args.no_check,
            };
            match run(&options, |_| {}) {
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
