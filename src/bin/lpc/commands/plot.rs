//! `lpc plot`: the paper's figures from a scene, a run directory or a compare directory.

use std::path::{Path, PathBuf};

use lpc_damper::model::RunOptions;
use lpc_damper::scene;
use lpc_damper::studies::chain::run_chain;
use lpc_damper::Model;

use crate::args::{invalid, override_scene, parse_size, BudgetArgs, ModelArgs};
use crate::exit::{ExitStatus, Result};

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (damper: Figs. 8-12; [sweep]: Figs. 13-16; [chain]: Fig. 5), a directory
    /// written by `lpc run --out` (its series; with `--ensemble`, also the members' band over
    /// the nominal run), or one written by `lpc compare --out` (overlay).
    input: PathBuf,
    /// Directory for the figures.
    #[arg(long)]
    out: PathBuf,
    /// Model that runs a scene.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Figure size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1000x640", value_parser = parse_size)]
    size: (u32, u32),
    #[command(flatten)]
    settings: ModelArgs,
    #[command(flatten)]
    budget: BudgetArgs,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    use lpc_damper::output::figures::{self, Figure};
    let limits = a.budget.limits(&a.input)?;
    let mut figs: Vec<Figure> = vec![];
    if a.input.is_dir() {
        let series = |dir: &Path| dir.join("series.csv");
        let name_of = |dir: &Path, key: &str| -> Option<String> {
            let text = std::fs::read(dir.join("summary.json")).ok()?;
            let v: serde_json::Value = serde_json::from_slice(&text).ok()?;
            v.get(key)?.as_str().map(str::to_string)
        };
        if series(&a.input).is_file() {
            let s = figures::read_series_csv(&series(&a.input))?;
            let model = name_of(&a.input, "model").and_then(|m| m.parse::<Model>().ok()).ok_or_else(|| {
                invalid(&a.input.join("summary.json"), "model", "is missing or names no model (expected a directory of `lpc run --out`)")
            })?;
            let mut run = lpc_damper::run::Run::empty(&name_of(&a.input, "scene").unwrap_or_else(|| "run".into()), model);
            run.series = s;
            figs.extend(figures::time_histories(&run, None));
            // A structure's floors, with the bare building's drift profile from its summary.
            let bare: Option<Vec<lpc_damper::metrics::FloorSummary>> = std::fs::read(a.input.join("summary.json"))
                .ok()
                .and_then(|text| serde_json::from_slice::<serde_json::Value>(&text).ok())
                .and_then(|v| serde_json::from_value(v.get("floors_without_damper")?.clone()).ok())
                .filter(|f: &Vec<_>| !f.is_empty());
            figs.extend(figures::floor_responses(&run, bare.as_deref()));
            figs.extend(figures::ball_positions(&run, None, &[]));
            // `lpc run --ensemble --out`: the members' band over the nominal run.
            let band = a.input.join("band.csv");
            if band.is_file() {
                figs.push(figures::band_chart(&run, &figures::read_band_csv(&band)?));
            }
        } else {
            let mut models = vec![];
            let mut entries: Vec<PathBuf> =
                std::fs::read_dir(&a.input)?.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| series(p).is_file()).collect();
            entries.sort();
            for dir in entries {
                let name = dir.file_name().map_or("model".into(), |n| n.to_string_lossy().into_owned());
                models.push((name, figures::read_series_csv(&series(&dir))?));
            }
            if models.is_empty() {
                return Err(invalid(
                    &a.input,
                    "input",
                    "holds no series.csv (expected a directory of `lpc run --out` or `lpc compare --out`)",
                )
                .into());
            }
            let scene_name = name_of(&a.input.join(&models[0].0), "scene").unwrap_or_default();
            figs.push(figures::overlay(&models, &scene_name));
        }
    } else {
        let loaded = scene::load(&a.input)?;
        if let Some(mut cases) = loaded.chain.clone() {
            for c in &mut cases {
                override_scene(&mut c.scene, a.settings.overrides(None, None), &a.input)?;
            }
            figs.push(figures::ker_chart(&run_chain(&cases, a.model, limits, &|| {})?, a.model.name()));
        } else if loaded.file.sweep.is_some() {
            use rayon::prelude::*;
            let mut scenes = lpc_damper::studies::sweep::sweep_scenes(&loaded)?;
            for (_, s) in &mut scenes {
                override_scene(s, a.settings.overrides(None, None), &a.input)?;
            }
            let parameter = loaded.file.sweep.as_ref().map_or(String::new(), |s| s.parameter.clone());
            let values: Vec<String> = loaded.file.sweep.as_ref().map_or(vec![], |s| s.values.iter().map(|v| v.to_string()).collect());
            let work = crate::watch::Work::new(Some(scenes.len()), "sweep");
            let runs = scenes
                .par_iter()
                .zip(values)
                .map(|((_, s), label)| {
                    let run = a.model.simulate(s, &RunOptions::limited(limits));
                    work.inc();
                    Ok((label, run?))
                })
                .collect::<std::result::Result<Vec<_>, lpc_damper::model::ModelError>>()?;
            work.finish();
            figs.push(figures::sweep_curves(&parameter, &runs));
        } else {
            let mut s = loaded.scene.clone().expect("a scene file without [chain] has [frame]");
            override_scene(&mut s, a.settings.overrides(None, None), &a.input)?;
            let run = crate::watch::watched(a.model, &s, RunOptions::limited(limits))?;
            let bare = crate::watch::watched(lpc_damper::Model::Reference, &s.without_damper(), RunOptions::limited(limits))?;
            figs.extend(figures::time_histories(&run, (!s.balls.is_empty()).then_some(&bare)));
            let bare_floors = lpc_damper::metrics::FloorSummary::of(&bare.series);
            figs.extend(figures::floor_responses(&run, (!s.balls.is_empty()).then_some(&bare_floors[..])));
            if !s.balls.is_empty() {
                let chains: Vec<_> = (0..s.space.chains()).map(|k| s.space.chain(k, s.balls.len())).collect();
                figs.extend(figures::ball_positions(&run, s.container.map(|c| c.length), &chains));
            }
        }
    }
    for f in &figs {
        for p in figures::write(f, &a.out, a.size)? {
            println!("{}", p.display());
        }
    }
    Ok(ExitStatus::Success)
}
