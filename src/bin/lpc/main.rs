//! `lpc`: the command-line tool. A thin layer over the library: parse the arguments, run one
//! command, turn how it ended into the exit code. Each command lives in `commands/` with its
//! own arguments; what several share is in `args`; how a command ends is `exit`.
//!
//! Exit status: 0 success; 1 a run failed (a model stalled or refused the scene, an output
//! could not be written); 2 bad input (a scene or a flag that cannot exist, a missing file);
//! 3 `lpc check` found a regression.

// The doc comments of the commands and their arguments are their `--help` text, where
// `[sweep]` names a table of the scene file, not an item to link to.
#![allow(rustdoc::broken_intra_doc_links)]

mod args;
mod commands;
mod exit;
mod table;
mod watch;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "lpc", version, about = "Simulate the Linear Particle Chain impact damper (Gharib & Ghani 2013)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run one model on a scene and print a summary (or write series, impacts and summary).
    Run(commands::run::Args),
    /// Run every value of a scene's [sweep] table, in parallel.
    Sweep(commands::sweep::Args),
    /// Join the shards of an ensemble (`lpc run --ensemble N --shard I/K --out DIR`) into one table.
    Merge(commands::merge::Args),
    /// Frequency response: steady amplitude of xs against forcing frequency, with and without
    /// the damper (needs a [forcing] table, or --kind and --amplitude).
    Frf(commands::frf::Args),
    /// Find the design (arrangement and parameters) with the shortest settling time or the
    /// lowest resonant amplitude inside a given container length.
    Optimize(commands::optimize::Args),
    /// The chain experiment (Fig. 5): kinetic energy ratio against the number of large balls.
    Chain(commands::chain::Args),
    /// Run several models on one scene and report each one's errors against the reference.
    Compare(commands::compare::Args),
    /// Run time against error for every model and setting; marks the Pareto front.
    Bench(commands::bench::Args),
    /// Random valid scenes through every model, checked for instability; failures shrunk.
    Stress(commands::stress::Args),
    /// Headless regression runs: every scene with every model against tests/golden/.
    Check(commands::check::Args),
    /// The contact model's stability map: step size x impact speed, with and without CCD.
    Stability(commands::stability::Args),
    /// The paper's figures (PNG and SVG) from a scene, a run directory or a compare directory.
    Plot(commands::plot::Args),
    /// Numbered PNG frames of a run in 3D, off-screen (needs `--features render`).
    Render(commands::render::Args),
    /// A run in an interactive 3D window (needs `--features render` and a display).
    View(commands::view::Args),
}

fn main() -> ExitCode {
    restore_sigpipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(a) => commands::run::run(a),
        Command::Sweep(a) => commands::sweep::run(a),
        Command::Merge(a) => commands::merge::run(a),
        Command::Frf(a) => commands::frf::run(a),
        Command::Optimize(a) => commands::optimize::run(a),
        Command::Chain(a) => commands::chain::run(a),
        Command::Compare(a) => commands::compare::run(a),
        Command::Bench(a) => commands::bench::run(a),
        Command::Stress(a) => commands::stress::run(a),
        Command::Check(a) => commands::check::run(a),
        Command::Stability(a) => commands::stability::run(a),
        Command::Plot(a) => commands::plot::run(a),
        Command::Render(a) => commands::render::run(a),
        Command::View(a) => commands::view::run(a),
    };
    let status = result.unwrap_or_else(|e| {
        eprintln!("error: {:#}", e.error);
        e.status
    });
    ExitCode::from(status)
}

/// Rust starts programs with SIGPIPE ignored, so writing to a closed pipe (`lpc check | head`)
/// makes `println!` panic. A command-line tool should end quietly instead, as Unix tools do.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any other thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
