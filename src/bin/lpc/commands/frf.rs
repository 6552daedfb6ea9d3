//! `lpc frf`: the steady amplitude of the frame against forcing frequency, with and without the damper.

use std::path::PathBuf;

use anyhow::Context;
use clap::ValueEnum;

use lpc_damper::files::write_atomic;
use lpc_damper::scene::{self, Overrides};
use lpc_damper::Model;

use crate::args::{invalid, load_nominal, parse_range, print_json, BudgetArgs, EnsembleArgs, Format, ModelArgs};
use crate::exit::{CommandError, ExitStatus, Result};
use crate::table::{right, Table};

#[derive(clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Frequency range `A..B` in Hz.
    #[arg(long)]
    freq: String,
    /// Number of frequencies, evenly spaced over the range.
    #[arg(long, default_value_t = 21)]
    steps: usize,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Forcing kind, when the scene has no [forcing] table (or to override it).
    #[arg(long, value_enum)]
    kind: Option<ForcingKindArg>,
    /// Forcing amplitude (N for a force, m for base motion), when the scene has no [forcing]
    /// table (or to override it).
    #[arg(long)]
    amplitude: Option<f64>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Write frf.json, frf.csv and the plot (frf.png, frf.svg) into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    settings: ModelArgs,
    #[command(flatten)]
    budget: BudgetArgs,
    #[command(flatten)]
    ensemble: EnsembleArgs,
}

#[derive(Clone, Copy, ValueEnum)]
enum ForcingKindArg {
    Force,
    Base,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let limits = a.budget.limits(&a.scene)?;
    let nominal = load_nominal(&a.scene, a.settings.overrides(None, None))?;
    let scene = nominal.scene.clone();
    let (from, to) = parse_range(&a.freq, &a.scene, "--freq")?;
    let invalid = |field: &str, rule: String| invalid(&a.scene, field, rule);
    if let Err(rule) = lpc_damper::studies::frf::check_frequency_count(a.steps) {
        return Err(invalid("--steps", rule).into());
    }
    let forcing = Overrides {
        forcing_kind: a.kind.map(|k| match k {
            ForcingKindArg::Force => scene::ForcingKind::Force,
            ForcingKindArg::Base => scene::ForcingKind::Base,
        }),
        forcing_amplitude: a.amplitude,
        forcing_frequency: (a.kind.is_some() || a.amplitude.is_some()).then_some(from),
        ..Overrides::default()
    };
    let scene = forcing.apply(scene, &a.scene.display().to_string())?;
    let Some(g) = scene.forcing else {
        return Err(invalid("forcing", "is missing: give the scene a [forcing] table, or --kind and --amplitude".into()).into());
    };
    if g.amplitude == 0.0 {
        return Err(invalid("forcing.amplitude", "is 0: give --amplitude".into()).into());
    }
    if let Some(natural) = scene.frame.and_then(|f| f.resonance_without_steady_state(from, to)) {
        return Err(invalid(
            "--freq",
            format!("{from}..{to} Hz contains the undamped frame's resonance {natural:.6} Hz, where no steady state exists"),
        )
        .into());
    }
    let freqs = lpc_damper::studies::frf::frequencies(from, to, a.steps);
    if let Some(count) = a.ensemble.ensemble {
        lpc_damper::studies::frf::check_ensemble_memory(count, freqs.len()).map_err(|rule| invalid("--ensemble", rule))?;
    }
    if let Some(members) = nominal.ensemble_of(a.ensemble, &nominal.file, &scene)? {
        return frf_ensemble(&a, &scene, &members, &freqs);
    }
    let work = crate::watch::Work::new(Some(2 * freqs.len()), "frf");
    let start = std::time::Instant::now();
    let points = lpc_damper::studies::frf::frf(&scene, &freqs, a.model, limits, &|| work.inc());
    work.finish();
    let elapsed = start.elapsed().as_secs_f64();
    if let Some(dir) = &a.out {
        write_atomic(&dir.join("frf.json"), &serde_json::to_vec_pretty(&points)?).with_context(|| format!("writing {}", dir.display()))?;
        // The carrying floor's columns; a structure's every floor goes to frf-floors.csv, a row
        // per frequency and floor.
        let mut w = csv::Writer::from_writer(Vec::new());
        for p in &points {
            w.serialize(lpc_damper::studies::frf::FrfPoint { floors: None, floors_no_damper: None, ..p.clone() })?;
        }
        write_atomic(&dir.join("frf.csv"), &w.into_inner()?).with_context(|| format!("writing {}", dir.display()))?;
        let floor_rows = lpc_damper::studies::frf::floor_rows(&points);
        if !floor_rows.is_empty() {
            let mut w = csv::Writer::from_writer(Vec::new());
            for row in &floor_rows {
                w.serialize(row)?;
            }
            write_atomic(&dir.join("frf-floors.csv"), &w.into_inner()?).with_context(|| format!("writing {}", dir.display()))?;
        }
        let fig = lpc_damper::output::figures::frf_chart(&points, &scene.name, a.model.name());
        lpc_damper::output::figures::write(&fig, dir, (900, 560))?;
    }
    match a.format {
        Format::Json => print_json(&points)?,
        Format::Text => {
            println!(
                "frequency response of {} ({}, {:?} forcing, amplitude {}; {} runs in {:.2} s)",
                scene.name,
                a.model.name(),
                g.kind,
                g.amplitude,
                2 * points.len(),
                elapsed
            );
            let table = Table::new(vec![
                right("f Hz", 10),
                right("amp mm", 14),
                right("no damper mm", 14),
                right("ratio", 8),
                right("impacts/period", 16),
                right("steady (with/without)", 22),
            ]);
            table.print_header();
            let mm = |x: Option<f64>| x.map_or("failed".to_string(), |x| format!("{:.4}", x * 1e3));
            for p in &points {
                let ratio = match (p.amplitude, p.amplitude_no_damper) {
                    (Some(a), Some(b)) => format!("{:.3}", a / b),
                    _ => "-".into(),
                };
                table.print_row(&[
                    format!("{:.4}", p.frequency),
                    mm(p.amplitude),
                    mm(p.amplitude_no_damper),
                    ratio,
                    p.impacts_per_period.map_or("-".into(), |x| format!("{x:.2}")),
                    format!("{}/{}", if p.steady { "yes" } else { "no" }, if p.steady_no_damper { "yes" } else { "no" }),
                ]);
            }
            let floor_rows = lpc_damper::studies::frf::floor_rows(&points);
            if !floor_rows.is_empty() {
                println!("every floor's steady amplitude relative to the ground (floor 1 at the bottom)");
                let table = Table::new(vec![right("f Hz", 10), right("floor", 6), right("amp mm", 14), right("no damper mm", 14)]);
                table.print_header();
                for row in &floor_rows {
                    table.print_row(&[
                        format!("{:.4}", row.frequency),
                        row.floor.to_string(),
                        mm(row.amplitude),
                        mm(row.amplitude_no_damper),
                    ]);
                }
            }
            for p in points.iter().filter(|p| p.error.is_some()) {
                println!("{} Hz failed: {}", lpc_damper::scene::human(p.frequency), p.error.as_deref().unwrap_or_default());
            }
            if let Some(dir) = &a.out {
                let floors = if floor_rows.is_empty() { "" } else { "frf-floors.csv, " };
                println!("wrote frf.json, frf.csv, {floors}frf.png, frf.svg to {}", dir.display());
            }
        }
    }
    let failed = points.iter().filter(|p| p.error.is_some()).count();
    if failed > 0 {
        return Err(CommandError::failure(anyhow::anyhow!("{failed} of {} frequencies failed (see above)", points.len())));
    }
    Ok(ExitStatus::Success)
}

/// The response over an ensemble: per frequency the distribution of the per-period peaks.
fn frf_ensemble(a: &Args, scene: &scene::Scene, members: &lpc_damper::studies::ensemble::Ensemble, freqs: &[f64]) -> Result<ExitStatus> {
    let work = crate::watch::Work::new(Some(2 * freqs.len() * members.members.len()), "frf");
    let start = std::time::Instant::now();
    let bands = lpc_damper::studies::frf::frf_ensemble(&members.members, freqs, a.model, a.budget.limits(&a.scene)?, &|| work.inc());
    work.finish();
    let elapsed = start.elapsed().as_secs_f64();
    if let Some(dir) = &a.out {
        write_atomic(&dir.join("frf.json"), &serde_json::to_vec_pretty(&bands)?).with_context(|| format!("writing {}", dir.display()))?;
        let fig = lpc_damper::output::figures::frf_band_chart(&bands, &scene.name, a.model.name());
        lpc_damper::output::figures::write(&fig, dir, (900, 560))?;
    }
    match a.format {
        Format::Json => print_json(&bands)?,
        Format::Text => {
            println!(
                "frequency response of {} over {} members ({}; {} runs in {:.2} s): per-period peaks of the last {} periods",
                scene.name,
                members.members.len(),
                a.model.name(),
                2 * freqs.len() * members.members.len(),
                elapsed,
                2 * lpc_damper::studies::frf::BLOCK_PERIODS
            );
            let table = Table::new(vec![
                right("f Hz", 10),
                right("median mm", 12),
                right("5-95 % mm", 20),
                right("no damper mm", 14),
                right("5-95 % mm", 20),
                right("steady members", 16),
            ]);
            table.print_header();
            let mm = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{:.4}", x * 1e3));
            for b in &bands {
                table.print_row(&[
                    format!("{:.4}", b.frequency),
                    mm(b.amplitude.median),
                    format!("{}-{}", mm(b.amplitude.p05), mm(b.amplitude.p95)),
                    mm(b.amplitude_no_damper.median),
                    format!("{}-{}", mm(b.amplitude_no_damper.p05), mm(b.amplitude_no_damper.p95)),
                    format!("{}/{}", b.steady_members, b.members),
                ]);
            }
            for b in bands.iter().filter(|b| b.error.is_some()) {
                println!("{} Hz failed: {}", lpc_damper::scene::human(b.frequency), b.error.as_deref().unwrap_or_default());
            }
        }
    }
    let failed = bands.iter().filter(|b| b.error.is_some()).count();
    if failed > 0 {
        return Err(CommandError::failure(anyhow::anyhow!("{failed} of {} frequencies failed (see above)", bands.len())));
    }
    Ok(ExitStatus::Success)
}
