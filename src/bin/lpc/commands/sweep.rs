//! `lpc sweep`: a scene's [sweep] table, or one or two axes given as flags (a design map), in parallel.

use std::path::PathBuf;

use anyhow::Context;

use lpc_damper::files::write_atomic;
use lpc_damper::metrics::{Headline, Metric};
use lpc_damper::output::parquet::{provenance, table_parquet, Constant};
use lpc_damper::scene;
use lpc_damper::Model;

use lpc_damper::studies::ensemble;
use lpc_damper::studies::sweep::{Axis, Coordinates, EnsemblePoint, GridScene, SweepPoint};

use crate::args::{invalid, override_scene, print_json, quantile_arg, BudgetArgs, EnsembleArgs, Format, ModelArgs, Nominal};
use crate::exit::{ExitStatus, Result};
use crate::table::{right, statistic, Table};

#[derive(clap::Args)]
pub struct Args {
    /// Scene file with a [sweep] table.
    scene: PathBuf,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Simulated time, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Also write sweep.json, sweep.parquet (one row per cell) and, for a grid, the design map
    /// sweep-map.png/.svg into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
    /// First axis instead of the file's [sweep]: `PARAM=V1,V2,...` or `PARAM=A..B:N`
    /// (lengths may be `0.5Rr`).
    #[arg(long)]
    x: Option<String>,
    /// Second axis (makes a grid): same syntax as --x.
    #[arg(long)]
    y: Option<String>,
    /// Metric of the design map: any metric of a run's summary (settling_time,
    /// energy_remaining, dissipation_time_99, peak_displacement, impact_count, ...).
    #[arg(long, default_value = "settling_time")]
    metric: Metric,
    #[command(flatten)]
    settings: ModelArgs,
    #[command(flatten)]
    budget: BudgetArgs,
    #[command(flatten)]
    ensemble: EnsembleArgs,
    /// With --ensemble: the quantile of each cell's distribution that the map shows (default
    /// 0.5, the median).
    #[arg(long, requires = "ensemble")]
    quantile: Option<f64>,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let limits = a.budget.limits(&a.scene)?;
    let loaded = scene::load(&a.scene)?;
    let invalid = |field: &str, rule: String| invalid(&a.scene, field, rule);
    let mut axes = match &a.x {
        Some(x) => vec![lpc_damper::studies::sweep::parse_axis(x).map_err(|rule| invalid("--x", rule))?],
        None if a.y.is_some() => return Err(invalid("--y", "needs --x".into()).into()),
        None => lpc_damper::studies::sweep::file_axes(&loaded)?,
    };
    if let Some(y) = &a.y {
        axes.truncate(1);
        axes.push(lpc_damper::studies::sweep::parse_axis(y).map_err(|rule| invalid("--y", rule))?);
    }
    if loaded.scene.is_none() {
        return Err(invalid("frame", "is missing: a sweep needs a damper scene".into()).into());
    }
    let mut grid = lpc_damper::studies::sweep::grid_scenes(&loaded, &axes)?;
    for g in &mut grid {
        override_scene(&mut g.scene, a.settings.overrides(a.horizon, None), &a.scene)?;
    }
    let parameters: Vec<String> = axes.iter().map(|x| x.parameter.to_string()).collect();
    if a.ensemble.ensemble.is_some() {
        let q = quantile_arg(a.quantile, &a.scene)?;
        let nominal = Nominal::of(&loaded, a.settings.overrides(a.horizon, None))?;
        return sweep_ensembles(&a, &nominal, &axes, &parameters, &grid, q);
    }
    let parameter = parameters.join(" x ");
    let work = crate::watch::Work::new(Some(grid.len()), "sweep");
    let start = std::time::Instant::now();
    let points = lpc_damper::studies::sweep::run_grid(&parameters, &grid, a.model, limits, &|| work.inc())?;
    work.finish();
    let elapsed = start.elapsed().as_secs_f64();
    if let Some(dir) = &a.out {
        let cells: Vec<Option<f64>> = points.iter().map(|p| Headline::of_summary(&p.summary).value(a.metric)).collect();
        let title = format!("{}: {} ({})", loaded.scene.as_ref().map_or("", |s| s.name.as_str()), a.metric, a.model.name());
        let numbered: Vec<(usize, SweepPoint)> = points.iter().cloned().enumerate().collect();
        let (header, rows) = lpc_damper::studies::sweep::cells_table(&parameters, &numbered);
        let table = SweepTable { header, rows, constants: provenance(a.model, None) };
        write_sweep(dir, &points, &axes, &cells, title, a.metric.to_string(), &table)?;
    }
    match a.format {
        Format::Json => print_json(&points)?,
        Format::Text => {
            println!(
                "sweep of `{parameter}` ({}, {} runs in {:.3} s: {:.1} scene-runs per second)",
                a.model.name(),
                points.len(),
                elapsed,
                points.len() as f64 / elapsed
            );
            let mut columns: Vec<_> = parameters.iter().map(|p| right(p.as_str(), 12)).collect();
            columns.extend([
                right("impacts", 8),
                right("peak xs mm", 12),
                right("peak a m/s2", 12),
                right("rms xs mm", 10),
                right("settle s", 10),
                right("E left %", 9),
            ]);
            // A structure's designs on different floors are compared by the whole building.
            let building = points.iter().any(|p| p.summary.metrics.peak_drift.is_some());
            if building {
                columns.extend([right("drift mm", 10), right("roof mm", 10), right("floor a m/s2", 13)]);
            }
            let table = Table::new(columns);
            table.print_header();
            for p in &points {
                let m = &p.summary.metrics;
                let mut cells = vec![p.at.value.to_string()];
                cells.extend(p.at.value_y.map(|v| v.to_string()));
                cells.extend([
                    p.summary.impact_count.to_string(),
                    format!("{:.4}", m.peak_displacement * 1e3),
                    format!("{:.4}", m.peak_acceleration),
                    format!("{:.4}", m.rms_displacement * 1e3),
                    m.settling_time.map_or("-".into(), |t| format!("{t:.3}")),
                    m.energy_remaining.map_or("-".into(), |e| format!("{:.3}", e * 100.0)),
                ]);
                if building {
                    let show = |x: Option<f64>, unit: f64| x.map_or("-".into(), |x| format!("{:.4}", x * unit));
                    cells.extend([show(m.peak_drift, 1e3), show(m.peak_roof_displacement, 1e3), show(m.peak_floor_acceleration, 1.0)]);
                }
                table.print_row(&cells);
            }
            if let (Some(dir), 2) = (&a.out, axes.len()) {
                println!("wrote sweep.json, sweep-map.png, sweep-map.svg to {}", dir.display());
            }
        }
    }
    Ok(ExitStatus::Success)
}

/// An axis's parameter, with `(Rr)` when its values are multiples of the reference radius.
fn axis_title(axis: &lpc_damper::studies::sweep::Axis) -> String {
    let rr = axis.values.iter().any(|v| matches!(v, scene::Length::Rr(_)));
    if rr {
        format!("{} (Rr)", axis.parameter)
    } else {
        axis.parameter.to_string()
    }
}

/// `sweep.json` of `points` and, for a grid, its design map of `cells` (grid order, first
/// axis fastest).
/// The rows of `sweep.parquet`, and the constants every row carries.
struct SweepTable {
    header: Vec<String>,
    rows: Vec<Vec<Option<f64>>>,
    constants: Vec<(&'static str, Constant)>,
}

fn write_sweep(
    dir: &std::path::Path,
    points: &impl serde::Serialize,
    axes: &[Axis],
    cells: &[Option<f64>],
    title: String,
    z_desc: String,
    table: &SweepTable,
) -> anyhow::Result<()> {
    write_atomic(&dir.join("sweep.json"), &serde_json::to_vec_pretty(points)?).with_context(|| format!("writing {}", dir.display()))?;
    let parquet = table_parquet(&table.header, &table.rows, lpc_damper::studies::sweep::INTEGER_COLUMNS, &table.constants)?;
    write_atomic(&dir.join("sweep.parquet"), &parquet).with_context(|| format!("writing {}", dir.display()))?;
    if axes.len() != 2 {
        return Ok(());
    }
    let (nx, ny) = (axes[0].values.len(), axes[1].values.len());
    let map = lpc_damper::output::figures::HeatMap {
        name: "sweep-map".into(),
        title,
        x: (axis_title(&axes[0]), axes[0].values.iter().map(|v| v.raw()).collect()),
        y: (axis_title(&axes[1]), axes[1].values.iter().map(|v| v.raw()).collect()),
        z: (0..ny).map(|r| cells[r * nx..(r + 1) * nx].to_vec()).collect(),
        z_desc,
    };
    lpc_damper::output::figures::write_heat_map(&map, dir, (900, 640))?;
    Ok(())
}

/// Every point of the sweep an ensemble about it: each cell a distribution, the map its
/// `q` quantile.
fn sweep_ensembles(a: &Args, nominal: &Nominal, axes: &[Axis], parameters: &[String], grid: &[GridScene], q: f64) -> Result<ExitStatus> {
    let per_point = a.ensemble.ensemble.unwrap_or(1);
    let work = crate::watch::Work::new(Some(grid.len().saturating_mul(per_point)), "sweep");
    let start = std::time::Instant::now();
    let mut points = vec![];
    for g in grid {
        let Some(members) = nominal.ensemble_of(a.ensemble, &g.file, &g.scene)? else { continue };
        let runs = ensemble::run_members(&members, a.model, a.budget.limits(&a.scene)?, false, &|| work.inc())?;
        points.push(EnsemblePoint {
            at: Coordinates::of(parameters, &g.values),
            members: members.members.len(),
            redraws: members.redraws,
            metrics: ensemble::metric_stats(&runs.metrics),
            quantile: q,
            at_quantile: ensemble::metric_quantiles(&runs.metrics, q),
        });
    }
    work.finish();
    let elapsed = start.elapsed().as_secs_f64();
    if let Some(dir) = &a.out {
        let cells: Vec<Option<f64>> = points.iter().map(|p| p.at_quantile[a.metric.name()]).collect();
        let title = format!("{}: {} at quantile {q} of {per_point} members ({})", nominal.scene.name, a.metric, a.model.name());
        // One row per cell: each metric at the quantile the map shows.
        let mut header = vec!["cell".to_string()];
        header.extend(parameters.iter().cloned());
        header.extend(Metric::ALL.iter().map(|m| m.name().to_string()));
        let rows = points
            .iter()
            .enumerate()
            .map(|(cell, p)| {
                let mut row = vec![Some(cell as f64), Some(p.at.value)];
                if parameters.len() > 1 {
                    row.push(p.at.value_y);
                }
                row.extend(Metric::ALL.iter().map(|m| p.at_quantile[m.name()]));
                row
            })
            .collect();
        let mut constants = vec![("members", Constant::Unsigned(per_point as u64)), ("quantile", Constant::Text(q.to_string()))];
        constants.extend(provenance(a.model, None));
        let table = SweepTable { header, rows, constants };
        write_sweep(dir, &points, axes, &cells, title, format!("{} (q {q})", a.metric), &table)?;
    }
    match a.format {
        Format::Json => print_json(&points)?,
        Format::Text => {
            println!(
                "sweep of `{}` ({}, {} points x {per_point} members in {:.3} s): `{}` over the members",
                parameters.join(" x "),
                a.model.name(),
                points.len(),
                elapsed,
                a.metric
            );
            let mut columns: Vec<_> = parameters.iter().map(|p| right(p.as_str(), 12)).collect();
            columns.extend([right("median", 12), right("p05", 12), right("p95", 12), right(format!("q {q}"), 12), right("undefined", 10)]);
            let table = Table::new(columns);
            table.print_header();
            for p in &points {
                let s = &p.metrics[a.metric.name()];
                let mut cells = vec![p.at.value.to_string()];
                cells.extend(p.at.value_y.map(|v| v.to_string()));
                cells.extend([
                    statistic(s.median),
                    statistic(s.p05),
                    statistic(s.p95),
                    statistic(p.at_quantile[a.metric.name()]),
                    s.undefined.to_string(),
                ]);
                table.print_row(&cells);
            }
        }
    }
    Ok(ExitStatus::Success)
}
