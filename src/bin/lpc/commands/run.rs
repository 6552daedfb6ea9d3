//! `lpc run`: one model on one scene; a summary, or the series, impacts and summary files.
//! With `--ensemble N`, the distribution of every metric over N members drawn under the
//! scene's tolerances, and `members.csv`, `ensemble.json` and `band.csv`.

use std::path::{Path, PathBuf};

use anyhow::Context;

use lpc_damper::output::{table_csv, text_summary, write_atomic, write_run_dir, RunSummary, SUMMARY_METRICS};
use lpc_damper::studies::ensemble::{self, Ensemble, EnsembleSummary};
use lpc_damper::Model;

use crate::args::{load_nominal, print_json, progress_bar, EnsembleArgs, Format, RapierArgs};
use crate::exit::{ExitStatus, Result};
use crate::table::{left, right, statistic, Table};

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
    #[command(flatten)]
    ensemble: EnsembleArgs,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let nominal = load_nominal(&a.scene, a.rapier.overrides(a.horizon, a.sample_dt))?;
    if let Some(members) = nominal.ensemble(a.ensemble)? {
        return run_ensemble(&a, &nominal.scene, &members);
    }
    let scene = nominal.scene;
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

fn run_ensemble(a: &Args, nominal: &lpc_damper::scene::Scene, members: &Ensemble) -> Result<ExitStatus> {
    let bar = progress_bar(members.members.len(), "ensemble");
    let start = std::time::Instant::now();
    let runs = ensemble::run_members(members, a.model, a.out.is_some(), &|| bar.inc(1))?;
    let wall_time_s = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let summary = EnsembleSummary {
        scene: nominal.name.clone(),
        model: a.model,
        members: members.members.len(),
        redraws: members.redraws,
        seed: members.seed,
        metrics: ensemble::metric_stats(&runs.metrics),
        wall_time_s,
    };
    if let Some(dir) = &a.out {
        write_ensemble_dir(dir, a.model, nominal, members, &runs, &summary)
            .with_context(|| format!("writing outputs to {}", dir.display()))?;
    }
    match a.format {
        Format::Json => print_json(&summary)?,
        Format::Text => {
            println!(
                "scene {} | model {} | {} members (seed {}, {} redraws) | computed in {:.3} s ({:.1} us per member)",
                summary.scene,
                summary.model,
                summary.members,
                summary.seed,
                summary.redraws,
                wall_time_s,
                wall_time_s * 1e6 / summary.members as f64
            );
            let table = Table::new(vec![
                left("metric", 24),
                right("median", 12),
                right("p05", 12),
                right("p95", 12),
                right("mean", 12),
                right("std", 12),
                right("undefined", 10),
            ]);
            table.print_header();
            for name in SUMMARY_METRICS {
                let s = &summary.metrics[*name];
                table.print_row(&[
                    name.to_string(),
                    statistic(s.median),
                    statistic(s.p05),
                    statistic(s.p95),
                    statistic(s.mean),
                    statistic(s.std),
                    s.undefined.to_string(),
                ]);
            }
            if let Some(dir) = &a.out {
                println!("wrote members.csv, ensemble.json, band.csv and the nominal run to {}", dir.display());
            }
        }
    }
    Ok(ExitStatus::Success)
}

/// `members.csv` (each member's draws, then every metric), `ensemble.json`, `band.csv`, and
/// the nominal run's files, which `lpc plot DIR` draws the band over.
fn write_ensemble_dir(
    dir: &Path,
    model: Model,
    nominal: &lpc_damper::scene::Scene,
    members: &Ensemble,
    runs: &ensemble::EnsembleRuns,
    summary: &EnsembleSummary,
) -> anyhow::Result<()> {
    let run = model.simulate(nominal)?;
    write_run_dir(&run, dir)?;
    let mut header = vec!["member".to_string()];
    header.extend(members.columns.iter().cloned());
    header.extend(SUMMARY_METRICS.iter().map(|m| m.to_string()));
    let rows = members.members.iter().zip(&runs.metrics).map(|(m, metrics)| {
        let mut row = vec![Some(m.index as f64)];
        row.extend(m.drawn.iter().map(|&x| Some(x)));
        row.extend(metrics.iter().copied());
        row
    });
    write_atomic(&dir.join("members.csv"), &table_csv(&header, rows))?;
    write_atomic(&dir.join("ensemble.json"), &serde_json::to_vec_pretty(summary)?)?;
    let header: Vec<String> = ["t", "xs_p05", "xs_median", "xs_p95", "env_p95"].iter().map(|s| s.to_string()).collect();
    let band = ensemble::band(&runs.t, &runs.xs);
    write_atomic(&dir.join("band.csv"), &table_csv(&header, band.iter().map(|r| r.iter().map(|&x| Some(x)).collect())))?;
    Ok(())
}
