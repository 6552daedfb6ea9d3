//! `lpc bench`: run time against error for every model and setting, with the Pareto front.

use std::path::PathBuf;

use lpc_damper::files::write_atomic;
use lpc_damper::scene::Overrides;
use lpc_damper::Model;

use crate::args::{load_scene, print_json, TableFormat};
use crate::exit::{CommandError, ExitStatus, Result};
use crate::table::{right, Table};

/// Most runs per setting: the median of a thousand is as steady as timing gets.
const MAX_REPEAT: usize = 1000;

#[derive(clap::Args)]
pub struct Args {
    /// Scene files (default: the paper's damper scenes).
    scenes: Vec<PathBuf>,
    /// Models, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "reference,rapier,compliant")]
    models: Vec<Model>,
    /// Rapier steppings, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "fixed,aligned")]
    stepping: Vec<lpc_damper::scene::Stepping>,
    /// Rapier steps (longest steps when aligned), s, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.0001,0.0002,0.0005,0.001,0.002")]
    dt: Vec<f64>,
    /// Rapier solver iterations, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "4")]
    solver_iterations: Vec<u32>,
    /// Compliant model error tolerances, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1e-9")]
    tolerance: Vec<f64>,
    /// Runs per setting; the median time is reported.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Simulated time, s (overrides the scenes').
    #[arg(long)]
    horizon: Option<f64>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = TableFormat::Text)]
    format: TableFormat,
    /// Write bench.csv, bench.json and error_vs_cost.svg into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let paths = if a.scenes.is_empty() {
        ["conventional", "lpc-lsl", "lpc-lslsl", "chain-lll"].iter().map(|n| PathBuf::from(format!("scenes/{n}.toml"))).collect()
    } else {
        a.scenes.clone()
    };
    for &dt in &a.dt {
        Overrides { dt: Some(dt), ..Overrides::default() }.validate_settings()?;
    }
    for &it in &a.solver_iterations {
        Overrides { solver_iterations: Some(it), ..Overrides::default() }.validate_settings()?;
    }
    for &tolerance in &a.tolerance {
        Overrides { tolerance: Some(tolerance), ..Overrides::default() }.validate_settings()?;
    }
    if !(1..=MAX_REPEAT).contains(&a.repeat) {
        let rule = format!("must lie in 1..={MAX_REPEAT} (got {})", a.repeat);
        return Err(crate::args::invalid(std::path::Path::new("(command line)"), "--repeat", rule).into());
    }
    let plan = lpc_damper::studies::bench::Plan {
        models: a.models.clone(),
        steppings: a.stepping.clone(),
        dts: a.dt.clone(),
        solver_iterations: a.solver_iterations.clone(),
        tolerances: a.tolerance.clone(),
        repeat: a.repeat,
    };
    let per_scene = a.models.iter().map(|&m| plan.variants(m).len()).sum::<usize>();
    let work = crate::watch::Work::new(Some(per_scene * paths.len()), "bench");
    let mut rows = Vec::new();
    for p in &paths {
        let scene = load_scene(p, Overrides { horizon: a.horizon, ..Overrides::default() })?;
        rows.extend(lpc_damper::studies::bench::bench_scene(&scene, &plan, &|| work.inc())?);
    }
    work.finish();
    let csv_bytes = bench_csv(&rows)?;
    if let Some(dir) = &a.out {
        write_atomic(&dir.join("bench.csv"), &csv_bytes)?;
        write_atomic(&dir.join("bench.json"), &serde_json::to_vec_pretty(&rows)?)?;
        let svg = dir.join("error_vs_cost.svg");
        lpc_damper::output::plot::error_vs_cost(&rows, &svg)
            .map_err(|e| CommandError::failure(anyhow::anyhow!("drawing {}: {e}", svg.display())))?;
    }
    match a.format {
        TableFormat::Json => print_json(&rows)?,
        TableFormat::Csv => print!("{}", String::from_utf8(csv_bytes)?),
        TableFormat::Text => {
            let table = Table::new(vec![
                right("scene", 14),
                right("model", 9),
                right("stepping", 8),
                right("dt", 8),
                right("it", 4),
                right("s per sim s", 12),
                right("steps/s", 10),
                right("rms mm", 9),
                right("early mm", 11),
                right("settle s", 10),
                right("loss %", 9),
                right("pareto", 7),
            ]);
            table.print_header();
            for r in &rows {
                let e = &r.errors;
                table.print_row(&[
                    r.scene.clone(),
                    r.model.to_string(),
                    r.settings.stepping.to_string(),
                    // The compliant model has no step to set: its column shows the tolerance.
                    r.settings.dt.map(|d| format!("{d}")).or(r.settings.tolerance.map(|t| format!("tol {t:e}"))).unwrap_or("-".into()),
                    r.settings.solver_iterations.map_or("-".into(), |i| i.to_string()),
                    format!("{:.5}", r.wall_s_per_sim_s),
                    format!("{:.0}", r.steps_per_sim_s),
                    format!("{:.4}", e.rms_xs * 1e3),
                    format!("{:.5}", e.max_xs_early * 1e3),
                    e.settling_time_diff.map_or("n/a".into(), |d| format!("{d:+.3}")),
                    format!("{:.3}", e.impact_loss_diff * 100.0),
                    (if r.pareto { "*" } else { "" }).to_string(),
                ]);
            }
            if let Some(dir) = &a.out {
                println!("wrote bench.csv, bench.json, error_vs_cost.svg to {}", dir.display());
            }
        }
    }
    Ok(ExitStatus::Success)
}

fn bench_csv(rows: &[lpc_damper::studies::bench::BenchRow]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "scene",
        "model",
        "stepping",
        "dt",
        "solver_iterations",
        "wall_s_per_sim_s",
        "steps_per_sim_s",
        "rms_xs",
        "max_xs_early",
        "settling_time_diff",
        "impact_loss_diff",
        "impact_count_diff",
        "pareto",
        "tolerance",
    ])?;
    let opt = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
    for r in rows {
        let e = &r.errors;
        w.write_record([
            r.scene.clone(),
            r.model.to_string(),
            r.settings.stepping.to_string(),
            opt(r.settings.dt),
            r.settings.solver_iterations.map_or(String::new(), |i| i.to_string()),
            r.wall_s_per_sim_s.to_string(),
            r.steps_per_sim_s.to_string(),
            e.rms_xs.to_string(),
            e.max_xs_early.to_string(),
            opt(e.settling_time_diff),
            e.impact_loss_diff.to_string(),
            e.impact_count_diff.to_string(),
            r.pareto.to_string(),
            opt(r.settings.tolerance),
        ])?;
    }
    Ok(w.into_inner()?)
}
