//! `lpc run`: one model on one scene; a summary, or the series, impacts and summary files.
//! With `--ensemble N`, the distribution of every metric over N members drawn under the
//! scene's tolerances, and `members.csv`, `ensemble.json` and `band.csv`.

use std::path::{Path, PathBuf};

use anyhow::Context;

use lpc_damper::model::{ModelError, RunOptions};
use lpc_damper::run::ImpactRecord;
use lpc_damper::scene::Scene;

use lpc_damper::files::write_atomic;
use lpc_damper::metrics::{Metric, RunSummary};
use lpc_damper::output::parquet::{provenance, table_parquet};
use lpc_damper::output::{table_csv, text_summary, write_run_dir, write_run_dir_with};
use lpc_damper::studies::ensemble::{self, Ensemble, EnsembleSummary, ShardInfo};
use lpc_damper::Model;

use crate::args::{load_nominal, parse_shard, print_json, BudgetArgs, EnsembleArgs, Format, ModelArgs};
use crate::exit::{CommandError, ExitStatus, Result};
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
    settings: ModelArgs,
    #[command(flatten)]
    budget: BudgetArgs,
    /// Write series.csv, impacts.csv and summary.json into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
    /// What the run keeps of its impacts: every one (impacts.csv, the noise proxy's spreads),
    /// or only their count, for runs whose impacts outgrow memory (a long run of a pile makes
    /// hundreds of millions). Their energy is in the account either way. Ensemble members
    /// always count them; this applies to the nominal run that --ensemble --out writes.
    #[arg(long, value_name = "every|count", default_value = "every")]
    impacts: ImpactRecord,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// With --format json: print every impact in the summary too (by default it gives their
    /// count and the noise proxy; --out writes them to impacts.csv).
    #[arg(long)]
    print_impacts: bool,
    #[command(flatten)]
    ensemble: EnsembleArgs,
    /// With --ensemble: run only shard I (from 0) of K, members I*N/K .. (I+1)*N/K, the ones
    /// the whole ensemble has there (for a job array); --out then writes the shard's
    /// members.csv, members.parquet and shard.json, which `lpc merge` joins.
    #[arg(long, value_name = "I/K", requires = "ensemble", value_parser = parse_shard)]
    shard: Option<(usize, usize)>,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let limits = a.budget.limits(&a.scene)?;
    let nominal = load_nominal(&a.scene, a.settings.overrides(a.horizon, a.sample_dt))?;
    if let Some(shard) = a.shard {
        let members = nominal.ensemble_shard(a.ensemble, shard)?.expect("--shard requires --ensemble");
        return run_shard(&a, &nominal.scene, &members, shard);
    }
    if let Some(members) = nominal.ensemble(a.ensemble)? {
        return run_ensemble(&a, &nominal.scene, &members);
    }
    let scene = nominal.scene;
    // Said before the run, which may be long: the series it will keep.
    if let Ok(every @ 2..) = lpc_damper::run::series_every(&scene) {
        eprintln!(
            "note: scene `{}`: the series will keep one sample in {every} (one every {} s) so that it fits in the memory \
             left; the metrics use every sample",
            scene.name,
            lpc_damper::scene::human(scene.sample_dt * every as f64)
        );
    }
    let run = match crate::watch::watched_model(a.model, &scene, RunOptions { impacts: a.impacts, ..RunOptions::limited(limits) }) {
        Ok(run) => run,
        Err(e) => return Err(stopped(&a, &scene, e)),
    };
    let mut summary = RunSummary::of(&run);
    summary.dampers = lpc_damper::metrics::DamperSummary::of(&scene, &run);
    if scene.structure.is_some() && !scene.balls.is_empty() {
        // The structure alone, for the floors' response without the damper.
        let bare = a.model.simulate(&scene.without_damper(), &RunOptions::limited(limits))?;
        summary.floors_without_damper = lpc_damper::metrics::FloorSummary::of(&bare.series);
    }
    if let Some(dir) = &a.out {
        write_run_dir_with(&run, &summary, dir).with_context(|| format!("writing outputs to {}", dir.display()))?;
    }
    match a.format {
        Format::Json => print_summary_json(summary, a.print_impacts)?,
        Format::Text => {
            print!("{}", text_summary(&summary));
            if let Some(dir) = &a.out {
                let files = if summary.impacts_not_kept { "series.csv, summary.json" } else { "series.csv, impacts.csv, summary.json" };
                println!("wrote {files} to {}", dir.display());
            }
        }
    }
    Ok(ExitStatus::Success)
}

/// A run that could not reach its horizon: the run so far, when the model kept it, written to
/// `--out` and printed as JSON, both with the reason it stopped; then the error.
fn stopped(a: &Args, scene: &Scene, e: ModelError) -> CommandError {
    let reason = e.to_string();
    let summary = e.partial().map(|partial| {
        let dampers = lpc_damper::metrics::DamperSummary::of(scene, partial);
        (partial, RunSummary { stop: Some(reason.clone()), dampers, ..RunSummary::of(partial) })
    });
    if let (Some((partial, summary)), Some(dir)) = (&summary, &a.out) {
        if let Err(w) = write_run_dir_with(partial, summary, dir) {
            return CommandError::failure(anyhow::Error::new(w).context(format!("writing outputs to {}", dir.display())));
        }
        eprintln!("wrote the run up to t = {} s to {}", lpc_damper::scene::human(partial.horizon), dir.display());
    }
    if a.format == Format::Json {
        let printed = match summary {
            Some((_, summary)) => print_summary_json(summary, a.print_impacts),
            // Nothing of the run was kept: the reason alone, so a script reads why.
            None => print_json(&serde_json::json!({ "model": a.model, "stop": reason })),
        };
        if let Err(p) = printed {
            return p;
        }
    }
    e.into()
}

/// The summary on standard output: without the impact list unless `with_impacts` (a bed makes
/// millions; `impact_count` and the noise proxy say what they were, `impacts.csv` lists them).
fn print_summary_json(mut summary: RunSummary, with_impacts: bool) -> Result<()> {
    if with_impacts {
        return print_json(&summary);
    }
    summary.impacts = Vec::new();
    let mut value = serde_json::to_value(&summary)?;
    if let Some(fields) = value.as_object_mut() {
        fields.remove("impacts");
    }
    print_json(&value)
}

fn run_ensemble(a: &Args, nominal: &lpc_damper::scene::Scene, members: &Ensemble) -> Result<ExitStatus> {
    let work = crate::watch::Work::new(Some(members.members.len()), "ensemble");
    let start = std::time::Instant::now();
    let runs = ensemble::run_members(members, a.model, a.budget.limits(&a.scene)?, a.out.is_some(), &|| work.inc())?;
    let wall_time_s = start.elapsed().as_secs_f64();
    work.finish();
    let summary = EnsembleSummary::of(&nominal.name, a.model, members, &runs.metrics, wall_time_s);
    if let Some(dir) = &a.out {
        write_ensemble_dir(dir, a.model, a.impacts, nominal, members, &runs, &summary)
            .with_context(|| format!("writing outputs to {}", dir.display()))?;
    }
    print_ensemble(
        &summary,
        a.format,
        a.out.as_deref().map(|d| (d, "members.csv, members.parquet, ensemble.json, band.csv and the nominal run")),
    )
}

/// One shard of an ensemble: its members' table and `shard.json` for `lpc merge`.
fn run_shard(a: &Args, nominal: &lpc_damper::scene::Scene, members: &Ensemble, (shard, shards): (usize, usize)) -> Result<ExitStatus> {
    let work = crate::watch::Work::new(Some(members.members.len()), "shard");
    let start = std::time::Instant::now();
    let runs = ensemble::run_members(members, a.model, a.budget.limits(&a.scene)?, false, &|| work.inc())?;
    let wall_time_s = start.elapsed().as_secs_f64();
    work.finish();
    let first = members.members.first().map_or(0, |m| m.index);
    let info = ShardInfo {
        scene: nominal.name.clone(),
        model: a.model,
        seed: members.seed,
        members: a.ensemble.ensemble.unwrap_or(0),
        shard,
        shards,
        start: first,
        stop: first + members.members.len(),
        redraws: members.redraws,
        wall_time_s,
    };
    if let Some(dir) = &a.out {
        (|| -> anyhow::Result<()> {
            std::fs::create_dir_all(dir)?;
            write_members(dir, a.model, members.seed, &members.columns, members, &runs.metrics)?;
            write_atomic(&dir.join("shard.json"), &serde_json::to_vec_pretty(&info)?)?;
            Ok(())
        })()
        .with_context(|| format!("writing outputs to {}", dir.display()))?;
    }
    let summary = EnsembleSummary::of(&info.scene, a.model, members, &runs.metrics, wall_time_s);
    print_ensemble(&summary, a.format, a.out.as_deref().map(|d| (d, "members.csv, members.parquet and shard.json")))
}

/// `members.csv` and `members.parquet` of an ensemble's (or a shard's) members.
pub fn write_members(
    dir: &Path,
    model: Model,
    seed: u64,
    columns: &[String],
    members: &Ensemble,
    metrics: &[Vec<Option<f64>>],
) -> anyhow::Result<()> {
    let (header, rows) = ensemble::members_table(columns, &members.members, metrics);
    write_table(dir, "members", &header, &rows, model, seed)
}

/// `NAME.csv` and `NAME.parquet` of a members table.
pub fn write_table(dir: &Path, name: &str, header: &[String], rows: &[Vec<Option<f64>>], model: Model, seed: u64) -> anyhow::Result<()> {
    write_atomic(&dir.join(format!("{name}.csv")), &table_csv(header, rows.iter().cloned()))?;
    let constants = provenance(model, Some(seed));
    write_atomic(&dir.join(format!("{name}.parquet")), &table_parquet(header, rows, ensemble::INTEGER_COLUMNS, &constants)?)?;
    Ok(())
}

/// Prints an ensemble's summary; `wrote` names the directory and what went into it.
pub fn print_ensemble(summary: &EnsembleSummary, format: Format, wrote: Option<(&Path, &str)>) -> Result<ExitStatus> {
    let wall_time_s = summary.wall_time_s;
    match format {
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
            for metric in Metric::ALL {
                let name = metric.name();
                let s = &summary.metrics[name];
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
            if let Some((dir, what)) = wrote {
                println!("wrote {what} to {}", dir.display());
            }
        }
    }
    Ok(ExitStatus::Success)
}

/// `members.csv` (each member's draws, then every metric), `ensemble.json`, `band.csv`, and
/// the nominal run's files, which `lpc plot DIR` draws the band over; the nominal run keeps of
/// its impacts what `impacts` asks.
fn write_ensemble_dir(
    dir: &Path,
    model: Model,
    impacts: ImpactRecord,
    nominal: &lpc_damper::scene::Scene,
    members: &Ensemble,
    runs: &ensemble::EnsembleRuns,
    summary: &EnsembleSummary,
) -> anyhow::Result<()> {
    let run = model.simulate(nominal, &RunOptions { impacts, ..RunOptions::default() })?;
    write_run_dir(&run, dir)?;
    write_members(dir, model, members.seed, &members.columns, members, &runs.metrics)?;
    write_atomic(&dir.join("ensemble.json"), &serde_json::to_vec_pretty(summary)?)?;
    let header: Vec<String> = ["t", "xs_p05", "xs_median", "xs_p95", "env_p95"].iter().map(|s| s.to_string()).collect();
    let band = ensemble::band(&runs.t, &runs.xs);
    write_atomic(&dir.join("band.csv"), &table_csv(&header, band.iter().map(|r| r.iter().map(|&x| Some(x)).collect())))?;
    Ok(())
}
