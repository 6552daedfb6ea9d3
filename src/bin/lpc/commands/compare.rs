//! `lpc compare`: several models on one scene, each with its errors against the reference.

use std::path::PathBuf;

use anyhow::Context;

use lpc_damper::studies::compare::{errors, Errors};
use lpc_damper::output::{write_run_dir, RunSummary};
use lpc_damper::Model;

use crate::args::{load_scene, print_json, Format, RapierArgs};
use crate::table::{right, Table};
use crate::exit::{ExitStatus, Result};

#[derive(clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Models to compare with the reference, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "reference,rapier,compliant")]
    models: Vec<Model>,
    /// Simulated time, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    #[command(flatten)]
    rapier: RapierArgs,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Write each model's series.csv, impacts.csv and summary.json into DIR/MODEL/.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// One model's entry in `lpc compare`'s JSON.
#[derive(serde::Serialize)]
struct ModelComparison {
    summary: RunSummary,
    errors: Errors,
}

/// `lpc compare`'s JSON.
#[derive(serde::Serialize)]
struct Comparison {
    scene: String,
    reference: RunSummary,
    models: std::collections::BTreeMap<String, ModelComparison>,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let scene = load_scene(&a.scene, a.rapier.overrides(a.horizon, None))?;
    let reference = Model::Reference.simulate(&scene)?;
    let mut models = std::collections::BTreeMap::new();
    let mut runs = vec![];
    for &m in a.models.iter().filter(|m| **m != Model::Reference) {
        let run = m.simulate(&scene)?;
        models.insert(m.name().to_string(), ModelComparison { summary: RunSummary::of(&run), errors: errors(&run, &reference) });
        runs.push(run);
    }
    if let Some(dir) = &a.out {
        for run in std::iter::once(&reference).chain(&runs) {
            let d = dir.join(run.model.name());
            write_run_dir(run, &d).with_context(|| format!("writing outputs to {}", d.display()))?;
        }
    }
    let comparison = Comparison { scene: scene.name.clone(), reference: RunSummary::of(&reference), models };
    match a.format {
        Format::Json => print_json(&comparison)?,
        Format::Text => {
            let st = lpc_damper::rapier::settings(&scene);
            println!(
                "scene {} (rapier: {} steps, dt {} s, {} solver iterations)",
                scene.name,
                st.stepping.name(),
                st.dt,
                st.solver_iterations
            );
            let table = Table::new(vec![
                right("model", 10),
                right("wall ms", 10),
                right("x realtime", 10),
                right("rms xs mm", 12),
                right("early xs mm", 12),
                right("settle d s", 12),
                right("loss d %E0", 12),
                right("impacts (d)", 14),
            ]);
            table.print_header();
            let row = |name: &str, s: &RunSummary, e: Option<&Errors>| {
                let e = e.copied();
                table.print_row(&[
                    name.to_string(),
                    format!("{:.3}", s.wall_time_s * 1e3),
                    format!("{:.0}", s.horizon / s.wall_time_s),
                    e.map_or("-".into(), |e| format!("{:.4}", e.rms_xs * 1e3)),
                    e.map_or("-".into(), |e| format!("{:.4}", e.max_xs_early * 1e3)),
                    e.map_or("-".into(), |e| e.settling_time_diff.map_or("n/a".into(), |d| format!("{d:+.3}"))),
                    e.map_or("-".into(), |e| format!("{:+.3}", e.impact_loss_diff * 100.0)),
                    match e {
                        Some(e) => format!("{} ({:+})", s.impact_count, e.impact_count_diff),
                        None => s.impact_count.to_string(),
                    },
                ]);
            };
            row("reference", &comparison.reference, None);
            for (name, m) in &comparison.models {
                row(name, &m.summary, Some(&m.errors));
            }
            if let Some(dir) = &a.out {
                println!("wrote every model's series to {}/MODEL/", dir.display());
            }
        }
    }
    Ok(ExitStatus::Success)
}
