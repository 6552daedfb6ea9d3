//! `lpc run`: one model on one scene; a summary, or the series, impacts and summary files.

use std::path::PathBuf;

use anyhow::Context;

use lpc_damper::output::{text_summary, write_run_dir, RunSummary};
use lpc_damper::Model;

use crate::args::{load_scene, print_json, Format, RapierArgs};
use crate::exit::{ExitStatus, Result};

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML), e.g. scenes/lpc-lsl.toml.
    scene: PathBuf,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Simulated time, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    /// Output sampling step, s (default 1 ms).
    #[arg(long)]
    sample_dt: Option<f64>,
    #[command(flatten)]
    rapier: RapierArgs,
    /// Write series.csv, impacts.csv and summary.json into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let scene = load_scene(&a.scene, a.rapier.overrides(a.horizon, a.sample_dt))?;
    let run = a.model.simulate(&scene)?;
    let summary = RunSummary::of(&run);
    if let Some(dir) = &a.out {
        write_run_dir(&run, dir).with_context(|| format!("writing outputs to {}", dir.display()))?;
    }
    match a.format {
        Format::Json => print_json(&summary)?,
        Format::Text => {
            print!("{}", text_summary(&summary));
            if let Some(dir) = &a.out {
                println!("wrote series.csv, impacts.csv, summary.json to {}", dir.display());
            }
        }
    }
    Ok(ExitStatus::Success)
}
