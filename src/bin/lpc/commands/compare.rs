//! `lpc compare`: several models on one scene, each with its errors against the reference.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::Context;

use lpc_damper::metrics::RunSummary;
use lpc_damper::model::{ModelError, RunOptions};
use lpc_damper::output::write_run_dir;
use lpc_damper::scene::Scene;
use lpc_damper::studies::compare::{errors, Errors};
use lpc_damper::Model;

use lpc_damper::metrics::Metric;
use lpc_damper::studies::ensemble::{self, Agreement, Ensemble, Stats};

use crate::args::{load_nominal, print_json, BudgetArgs, EnsembleArgs, Format, ModelArgs};
use crate::exit::{ExitStatus, Result};
use crate::table::{left, right, statistic, Table};

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
    settings: ModelArgs,
    #[command(flatten)]
    budget: BudgetArgs,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Write each model's series.csv, impacts.csv and summary.json into DIR/MODEL/.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    ensemble: EnsembleArgs,
    /// Run the reference on the scene's frictionless copy (`world.friction = 0`), which it can
    /// represent; the other models run the scene as given, so their errors hold friction's
    /// effect as well as their own.
    #[arg(long)]
    frictionless_reference: bool,
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
    /// The friction the reference ran with (0 on the frictionless copy), beside the scene's.
    reference_friction: f64,
    friction: f64,
    reference: RunSummary,
    models: std::collections::BTreeMap<String, ModelComparison>,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let limits = a.budget.limits(&a.scene)?;
    let nominal = load_nominal(&a.scene, a.settings.overrides(a.horizon, None))?;
    if let Some(members) = nominal.ensemble(a.ensemble)? {
        return compare_ensembles(&a, &nominal.scene.name, &members);
    }
    let scene = nominal.scene;
    let copy = frictionless_copy(&scene, a.frictionless_reference)?;
    let reference_scene = copy.as_ref().unwrap_or(&scene);
    let reference = crate::watch::watched(Model::Reference, reference_scene, RunOptions::limited(limits))?;
    let mut models = std::collections::BTreeMap::new();
    let mut runs = vec![];
    for &m in a.models.iter().filter(|m| **m != Model::Reference) {
        let run = crate::watch::watched(m, &scene, RunOptions::limited(limits))?;
        models.insert(m.name().to_string(), ModelComparison { summary: RunSummary::of(&run), errors: errors(&run, &reference) });
        runs.push(run);
    }
    if let Some(dir) = &a.out {
        for run in std::iter::once(&reference).chain(&runs) {
            let d = dir.join(run.model.name());
            write_run_dir(run, &d).with_context(|| format!("writing outputs to {}", d.display()))?;
        }
    }
    let comparison = Comparison {
        scene: scene.name.clone(),
        reference_friction: reference_scene.space.friction,
        friction: scene.space.friction,
        reference: RunSummary::of(&reference),
        models,
    };
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
            if comparison.reference_friction != comparison.friction {
                println!(
                    "the reference runs the frictionless copy; the others friction {}: their errors hold friction's effect too",
                    comparison.friction
                );
            }
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

/// With `frictionless`, the copy of `scene` without friction that the reference runs; without,
/// `None` (the reference runs `scene`), and a scene with friction is refused with the reason
/// and the flag that runs it.
fn frictionless_copy(scene: &Scene, frictionless: bool) -> Result<Option<Scene>> {
    if frictionless {
        let mut smooth = scene.clone();
        smooth.space.friction = 0.0;
        return Ok(Some(smooth));
    }
    if scene.space.friction != 0.0 {
        if let Err(why) = Model::Reference.supports(scene) {
            // The flag helps only where friction is all the reference refuses.
            let mut smooth = scene.clone();
            smooth.space.friction = 0.0;
            if let Err(smooth_why) = Model::Reference.supports(&smooth) {
                return Err(ModelError::Refused(format!("{why}; and without friction, {smooth_why}")).into());
            }
            return Err(ModelError::Refused(format!(
                "{why}; `lpc compare --frictionless-reference` compares the others with the reference on the frictionless copy"
            ))
            .into());
        }
    }
    Ok(None)
}

/// One model's distributions in `lpc compare --ensemble`'s JSON.
#[derive(serde::Serialize)]
struct ModelDistributions {
    metrics: BTreeMap<String, Stats>,
    /// Against the reference's distribution, per metric.
    agreement: BTreeMap<String, Agreement>,
    wall_time_s: f64,
}

/// `lpc compare --ensemble`'s JSON.
#[derive(serde::Serialize)]
struct EnsembleComparison {
    scene: String,
    members: usize,
    seed: u64,
    redraws: u64,
    reference: ModelDistributions,
    models: BTreeMap<String, ModelDistributions>,
}

/// Every model on the same members; each model's distributions against the reference's.
fn compare_ensembles(a: &Args, scene: &str, members: &Ensemble) -> Result<ExitStatus> {
    let mut runs = BTreeMap::new();
    // The members the reference runs, when they are not `members` themselves.
    let mut smooth = None;
    for (k, member) in members.members.iter().enumerate() {
        if let Some(copy) = frictionless_copy(&member.scene, a.frictionless_reference)? {
            smooth.get_or_insert_with(|| members.clone()).members[k].scene = copy;
        }
    }
    for &m in std::iter::once(&Model::Reference).chain(a.models.iter().filter(|m| **m != Model::Reference)) {
        let work = crate::watch::Work::new(Some(members.members.len()), m.name());
        let start = std::time::Instant::now();
        let each = if m == Model::Reference { smooth.as_ref().unwrap_or(members) } else { members };
        let r = ensemble::run_members(each, m, a.budget.limits(&a.scene)?, false, &|| work.inc())?;
        work.finish();
        runs.insert(m, (r.metrics, start.elapsed().as_secs_f64()));
    }
    let reference = &runs[&Model::Reference].0;
    let distributions = |m: Model| {
        let (metrics, wall) = &runs[&m];
        ModelDistributions {
            metrics: ensemble::metric_stats(metrics),
            agreement: ensemble::agreement(metrics, reference),
            wall_time_s: *wall,
        }
    };
    let comparison = EnsembleComparison {
        scene: scene.to_string(),
        members: members.members.len(),
        seed: members.seed,
        redraws: members.redraws,
        reference: distributions(Model::Reference),
        models: runs.keys().filter(|m| **m != Model::Reference).map(|&m| (m.name().to_string(), distributions(m))).collect(),
    };
    match a.format {
        Format::Json => print_json(&comparison)?,
        Format::Text => {
            println!(
                "scene {} | {} members (seed {}, {} redraws): each model's median against the reference's 5-95 % band",
                comparison.scene, comparison.members, comparison.seed, comparison.redraws
            );
            let table = Table::new(vec![
                left("metric", 22),
                left("model", 10),
                right("median", 12),
                right("p05", 12),
                right("p95", 12),
                right("d median", 12),
                right("in band", 8),
                right("KS", 6),
                right("differ 5 %", 10),
            ]);
            table.print_header();
            for metric in Metric::ALL {
                let name = metric.name();
                let mut rows = vec![("reference", &comparison.reference)];
                rows.extend(comparison.models.iter().map(|(n, d)| (n.as_str(), d)));
                for (model, d) in rows {
                    let (s, g) = (&d.metrics[name], &d.agreement[name]);
                    if s.median.is_none() {
                        continue;
                    }
                    table.print_row(&[
                        name.to_string(),
                        model.to_string(),
                        statistic(s.median),
                        statistic(s.p05),
                        statistic(s.p95),
                        if model == "reference" { "-".into() } else { g.median_diff.map_or("-".into(), |x| format!("{x:+.5}")) },
                        g.median_inside_reference_band.map_or("-".into(), |b| if b { "yes" } else { "no" }.into()),
                        g.ks.map_or("-".into(), |k| format!("{k:.2}")),
                        g.differ_at_5_percent.map_or("-".into(), |b| if b { "yes" } else { "no" }.into()),
                    ]);
                }
            }
        }
    }
    Ok(ExitStatus::Success)
}
