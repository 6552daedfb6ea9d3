//! `lpc stress`: random valid scenes through the models, checked; failures shrunk to minimal scenes.

use std::path::PathBuf;

use lpc_damper::output::write_atomic;
use lpc_damper::Model;

use crate::args::{print_json, progress_bar, Format};
use crate::exit::{CommandError, ExitStatus, Result};

#[derive(clap::Args)]
pub struct Args {
    /// Scenes per model.
    #[arg(long, default_value_t = 200)]
    count: u64,
    /// First seed (scene k uses seed + k).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Models, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "reference,rapier")]
    models: Vec<Model>,
    /// Longest horizon drawn, s.
    #[arg(long, default_value_t = 100.0)]
    max_horizon: f64,
    /// Drive every scene by a harmonic force or base motion (from far below to far above the
    /// frame's resonance, from barely impacting to violent).
    #[arg(long)]
    forced: bool,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Write each failure's minimal scene into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let mut outcomes = Vec::new();
    let start = std::time::Instant::now();
    for &model in &a.models {
        let bar = progress_bar(a.count as usize, &format!("stress {}", model.name()));
        outcomes.extend(lpc_damper::studies::stress::stress(model, a.seed, a.count, a.max_horizon, a.forced, &|| bar.inc(1)));
        bar.finish_and_clear();
    }
    let failures: Vec<_> = outcomes.iter().filter(|o| o.failure.is_some()).collect();
    if let Some(dir) = &a.out {
        for o in &failures {
            let path = dir.join(format!("stress-{}-{}.toml", o.model, o.seed));
            write_atomic(&path, o.minimal_scene.as_deref().unwrap_or("").as_bytes())?;
        }
    }
    match a.format {
        Format::Json => print_json(&outcomes)?,
        Format::Text => {
            for o in &failures {
                let f = o.failure.as_ref().expect("failure");
                println!("FAIL {} seed {}: {} ({})", o.model, o.seed, f.check, f.detail);
                if let Some(m) = &o.minimal_scene {
                    println!("minimal scene:\n{m}");
                }
            }
            for &model in &a.models {
                let total = outcomes.iter().filter(|o| o.model == model).count();
                let failed = failures.iter().filter(|o| o.model == model).count();
                let refused = outcomes.iter().filter(|o| o.model == model && o.refused.is_some()).count();
                let unstable = outcomes.iter().filter(|o| o.model == model && o.refused_during_run).count();
                println!(
                    "{}: {} passed ({} of them refused with a reason, {} of those during the run), {} failed",
                    model.name(),
                    total - failed,
                    refused,
                    unstable,
                    failed
                );
            }
            println!("({:.1} s)", start.elapsed().as_secs_f64());
        }
    }
    if failures.is_empty() {
        Ok(ExitStatus::Success)
    } else {
        Err(CommandError::failure(anyhow::anyhow!("{} of {} stressed runs failed", failures.len(), outcomes.len())))
    }
}
