//! Arguments and helpers that several commands share: output formats, the Rapier model's
//! flags, loading a scene with command-line overrides, ranges and sizes, JSON and progress.

use std::io::Write;
use std::path::Path;

use clap::ValueEnum;

use lpc_damper::model::Limits;
use lpc_damper::scene::{self, Loaded, Overrides, Scene, SceneError, SceneFile, Stepping, Tolerances};
use lpc_damper::studies::ensemble::{self, Ensemble};

use crate::exit::Result;

/// Output format on standard output.
#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum Format {
    Text,
    Json,
}

/// Output format on standard output, for commands whose result is a table.
#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum TableFormat {
    Text,
    Json,
    Csv,
}

/// Settings of the models that every command accepts; each model reads its own and ignores
/// the others.
#[derive(clap::Args, Clone, Copy)]
pub struct ModelArgs {
    /// Rapier model: `aligned` (steps end at contacts) or `fixed` steps.
    #[arg(long)]
    stepping: Option<Stepping>,
    /// Rapier model: physics step (the longest one when aligned), s.
    #[arg(long)]
    dt: Option<f64>,
    /// Rapier model: solver iterations per step (overrides the scene's).
    #[arg(long)]
    solver_iterations: Option<u32>,
    /// Rapier model: turn on Rapier's swept CCD for the balls.
    #[arg(long)]
    ccd: bool,
    /// Compliant model: error tolerance per step, relative to the contact scales (default 1e-9).
    #[arg(long)]
    tolerance: Option<f64>,
}

/// What each run may cost; every command that runs a model accepts them.
#[derive(clap::Args, Clone, Copy)]
pub struct BudgetArgs {
    /// Stop a run after this many steps (the reference: events; the compliant model stops at
    /// 5e7 without one), saying what its steps cost and keeping the run so far (`lpc run`
    /// writes it with --out); in a study, the point of that run reports the stop.
    #[arg(long, value_name = "N")]
    max_steps: Option<u64>,
    /// Stop a run after this many seconds of computing, likewise.
    #[arg(long, value_name = "S")]
    max_wall_time: Option<f64>,
}

impl BudgetArgs {
    /// The budgets, checked by their rules (an error naming the flag and `scene`).
    pub fn limits(self, scene: &Path) -> Result<Limits> {
        let limits = Limits { max_steps: self.max_steps, max_wall_s: self.max_wall_time };
        limits.check().map_err(|(budget, rule)| invalid(scene, budget.flag().unwrap_or_default(), rule))?;
        Ok(limits)
    }
}

impl ModelArgs {
    /// These flags, with `--horizon` and `--sample-dt` where a command has them, as overrides
    /// that the scene module validates by the file's own rules.
    pub fn overrides(self, horizon: Option<f64>, sample_dt: Option<f64>) -> Overrides {
        Overrides {
            horizon,
            sample_dt,
            stepping: self.stepping,
            dt: self.dt,
            solver_iterations: self.solver_iterations,
            ccd: self.ccd,
            tolerance: self.tolerance,
            ..Overrides::default()
        }
    }
}

/// The scene at `path` with `overrides` applied (and validated) by the scene module.
pub fn load_scene(path: &Path, overrides: Overrides) -> std::result::Result<Scene, SceneError> {
    overrides.apply(scene::load_scene(path)?, &path.display().to_string())
}

/// `--ensemble N [--seed S]`: answer with distributions over members drawn under the scene's
/// `[tolerances]`.
#[derive(clap::Args, Clone, Copy, Default)]
pub struct EnsembleArgs {
    /// Run N members drawn under the scene's [tolerances] (in parallel) and report each
    /// metric's distribution instead of one trajectory's value.
    #[arg(long, value_name = "N")]
    pub ensemble: Option<usize>,
    /// Seed of the members' draws (default: the scene's tolerances.seed, else 1); member k's
    /// draws depend only on (seed, k).
    #[arg(long, requires = "ensemble")]
    pub seed: Option<u64>,
}

/// `I/K`: shard I (from 0) of K.
pub fn parse_shard(s: &str) -> std::result::Result<(usize, usize), String> {
    let bad = || format!("`{s}` is not a shard I/K (I from 0, K shards)");
    let (i, k) = s.split_once('/').ok_or_else(bad)?;
    Ok((i.trim().parse().map_err(|_| bad())?, k.trim().parse().map_err(|_| bad())?))
}

/// `--quantile Q` of a study over ensembles (default the median), checked.
pub fn quantile_arg(q: Option<f64>, path: &Path) -> std::result::Result<f64, SceneError> {
    ensemble::check_quantile(q.unwrap_or(0.5)).map_err(|rule| invalid(path, "--quantile", rule))
}

/// A scene file with its nominal scene (`overrides` applied) and what an ensemble draws from.
pub struct Nominal {
    pub path: String,
    pub file: SceneFile,
    pub tolerances: Option<Tolerances>,
    pub scene: Scene,
}

impl Nominal {
    /// The members `e` asks for, drawn about `scene` (this nominal scene or one varied from
    /// its file, as a sweep's point, with `file` the varied file); `None` without `--ensemble`.
    pub fn ensemble_of(&self, e: EnsembleArgs, file: &SceneFile, scene: &Scene) -> std::result::Result<Option<Ensemble>, SceneError> {
        e.ensemble
            .map(|n| {
                static NOTED: std::sync::Once = std::sync::Once::new();
                let random_bed = ensemble::places_bed_at_random(file);
                let random_ground = ensemble::shakes_at_random(file);
                if self.tolerances.is_none() {
                    NOTED.call_once(|| {
                        if random_bed {
                            eprintln!("note: {} has no [tolerances]: the members differ only in their beds' random placement", self.path)
                        } else if random_ground {
                            eprintln!("note: {} has no [tolerances]: the members differ only in their random ground motions", self.path)
                        } else {
                            eprintln!("note: {} has no [tolerances]: every member is the nominal scene", self.path)
                        }
                    });
                }
                ensemble::draw(file, &self.path, scene, self.tolerances.as_ref(), n, e.seed)
            })
            .transpose()
    }
    /// The members `e` asks for about the nominal scene.
    pub fn ensemble(&self, e: EnsembleArgs) -> std::result::Result<Option<Ensemble>, SceneError> {
        self.ensemble_of(e, &self.file, &self.scene)
    }
    /// The members of shard `(i, k)` of the ensemble `e` asks for ([`ensemble::shard_range`]).
    pub fn ensemble_shard(&self, e: EnsembleArgs, (i, k): (usize, usize)) -> std::result::Result<Option<Ensemble>, SceneError> {
        let Some(n) = e.ensemble else { return Ok(None) };
        if k == 0 || i >= k || k > n {
            return Err(invalid(Path::new(&self.path), "--shard", format!("must be I/K with 0 <= I < K <= N = {n} (got {i}/{k})")));
        }
        ensemble::draw_range(&self.file, &self.path, &self.scene, self.tolerances.as_ref(), n, ensemble::shard_range(n, i, k), e.seed)
            .map(Some)
    }
}

/// The damper scene at `path` with `overrides` applied, with its file and tolerances.
pub fn load_nominal(path: &Path, overrides: Overrides) -> std::result::Result<Nominal, SceneError> {
    Nominal::of(&scene::load(path)?, overrides)
}

impl Nominal {
    /// The damper scene of `loaded` with `overrides` applied, with its file and tolerances.
    pub fn of(loaded: &Loaded, overrides: Overrides) -> std::result::Result<Nominal, SceneError> {
        let scene = overrides.apply(loaded.damper()?.clone(), &loaded.path)?;
        Ok(Nominal { path: loaded.path.clone(), file: loaded.file.clone(), tolerances: loaded.tolerances.clone(), scene })
    }
}

/// Replaces `scene` (one of a sweep's or a chain's) by itself with `overrides` applied and
/// validated by the scene module.
pub fn override_scene(scene: &mut Scene, overrides: Overrides, path: &Path) -> std::result::Result<(), SceneError> {
    *scene = overrides.apply(scene.clone(), &path.display().to_string())?;
    Ok(())
}

/// A flag (or a field of the scene at `path`) that breaks `rule`.
pub fn invalid(path: &Path, field: &str, rule: impl Into<String>) -> SceneError {
    SceneError::Invalid { file: path.display().to_string(), field: field.into(), rule: rule.into() }
}

/// `WIDTHxHEIGHT` in pixels, each between 100 and 8000.
pub fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not a size WIDTHxHEIGHT between 100x100 and 8000x8000");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if !(100..=8000).contains(&w) || !(100..=8000).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

/// A frequency range `A..B` (positive, increasing) given as `field`.
pub fn parse_range(text: &str, path: &Path, field: &str) -> std::result::Result<(f64, f64), SceneError> {
    let invalid = |rule: String| invalid(path, field, rule);
    let (a, b) = text.split_once("..").ok_or_else(|| invalid(format!("`{text}` is not a range: write `A..B`")))?;
    let num = |s: &str| s.trim().parse::<f64>().map_err(|_| invalid(format!("`{s}` in `{text}` is not a number")));
    let (a, b) = (num(a)?, num(b)?);
    if !(a.is_finite() && b.is_finite() && a > 0.0 && b >= a) {
        return Err(invalid(format!("`{text}` must be positive and increasing")));
    }
    Ok((a, b))
}

/// `value` as pretty JSON on standard output.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    // Streamed: a long run's summary holds every impact, and its text is several times their
    // memory.
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    serde_json::to_writer_pretty(&mut out, value)?;
    writeln!(out)?;
    out.flush()?;
    Ok(())
}
