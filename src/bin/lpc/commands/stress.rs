//! `lpc stress`: random valid scenes through the models, checked; failures shrunk to minimal scenes.

use std::path::PathBuf;

use lpc_damper::files::write_atomic;
use lpc_damper::Model;

use crate::args::{print_json, Format};
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
    /// Draw the extremes a user can type instead of plausible dampers: 1-10 000 balls, frame
    /// periods 1 us-1000 s, mass ratios up to 1e9, densities 1e-3-1e6, gaps, clearances and
    /// displacements from 0 to far beyond the container, horizons up to 1e4 s.
    #[arg(long, conflicts_with = "forced")]
    extreme: bool,
    /// Draw each plausible scene as 1 to 4 copies of its chain side by side (the rest of the
    /// scene as without the flag).
    #[arg(long, conflicts_with = "extreme")]
    chains: bool,
    /// Draw each plausible scene's balls as a bed in a box instead (2-200 balls of one or two
    /// sizes, on a lattice or at random, gravity three times in four, friction 0-0.5, the
    /// reference's contact duration 1 us or, half the time, drawn up to 0.25 ms).
    #[arg(long, conflicts_with_all = ["extreme", "chains"])]
    beds: bool,
    /// Draw each plausible scene's frame as a floor of a building of 1 to 5 storeys (floors of
    /// 0.3-3 times its mass, storeys of 0.3-3 times its stiffness, Rayleigh damping), shaken
    /// by random ground motion a third of the time when not forced. With --beds, the bed rides
    /// the building (the contact and compliant models run it, the reference when it is
    /// frictionless).
    #[arg(long, conflicts_with = "extreme")]
    structures: bool,
    /// With --beds, draw each bed as two dampers in copies of its box, the second holding 1 to as
    /// many balls on a floor drawn at random (every model runs them; the reference when they are
    /// frictionless).
    #[arg(long, requires = "beds")]
    dampers: bool,
    /// Seconds of computing each run may take; a run that takes longer stops (a typed stop,
    /// counted apart from passes and failures). Default: none, 10 s with --extreme.
    #[arg(long, value_name = "S")]
    max_wall_time: Option<f64>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Write each failure's minimal scene into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let budget = lpc_damper::model::Limits { max_wall_s: a.max_wall_time, ..lpc_damper::model::Limits::NONE };
    budget.check().map_err(|(_, rule)| lpc_damper::scene::SceneError::Invalid {
        file: "(command line)".into(),
        field: "--max-wall-time".into(),
        rule,
    })?;
    let command_line =
        |field: &str, rule: String| lpc_damper::scene::SceneError::Invalid { file: "(command line)".into(), field: field.into(), rule };
    if !(a.max_horizon > 0.0 && a.max_horizon.is_finite()) {
        return Err(command_line("--max-horizon", format!("must be a positive number of seconds (got {})", a.max_horizon)).into());
    }
    if a.seed.checked_add(a.count).is_none() {
        return Err(command_line("--seed", format!("plus --count must stay below {} (got {} + {})", u64::MAX, a.seed, a.count)).into());
    }
    let draws = lpc_damper::studies::stress::Draws {
        max_horizon: a.max_horizon,
        forced: a.forced,
        extreme: a.extreme,
        chains: a.chains,
        beds: a.beds,
        structures: a.structures,
        dampers: a.dampers,
        max_wall_s: a.max_wall_time.or(a.extreme.then_some(10.0)),
    };
    let mut outcomes = Vec::new();
    let start = std::time::Instant::now();
    for &model in &a.models {
        let work = crate::watch::Work::new(Some(a.count as usize), &format!("stress {}", model.name()));
        outcomes.extend(lpc_damper::studies::stress::stress(model, a.seed, a.count, draws, &|| work.inc()));
        work.finish();
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
                let stopped = outcomes.iter().filter(|o| o.model == model && o.stopped.is_some()).count();
                println!(
                    "{}: {} passed ({} of them refused with a reason, {} of those during the run), {} stopped at the time budget, {} failed",
                    model.name(),
                    total - failed - stopped,
                    refused,
                    unstable,
                    stopped,
                    failed
                );
                let mut walls: Vec<(f64, u64)> = outcomes.iter().filter(|o| o.model == model).map(|o| (o.wall_s, o.seed)).collect();
                walls.sort_by(|a, b| a.0.total_cmp(&b.0));
                if let Some(&(slowest, seed)) = walls.last() {
                    let at = |q: f64| walls[((walls.len() - 1) as f64 * q).round() as usize].0;
                    println!(
                        "  computing time per scene (one core): median {:.3} s, 95 % {:.3} s, slowest {:.3} s (seed {seed})",
                        at(0.5),
                        at(0.95),
                        slowest
                    );
                }
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
