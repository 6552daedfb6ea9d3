//! Headless regression runs (`lpc check`): every scene of a directory with every model, its
//! summary compared with a golden file under a stated tolerance per metric.
//!
//! Tolerances: the reference is exact, so its metrics must agree to 1e-9 relative (room for a
//! different libm) and its impact count exactly. The contact model is deterministic on one
//! machine, but f32 arithmetic and another libm perturb it by about 1e-7 relative, and the
//! paper scenes amplify such perturbations (docs/BENCHMARKS.md, "Sensitivity"): a 1e-6
//! perturbation of the exact model moves the RMS displacement by up to 0.5 mm, the settling
//! time by up to 0.8 s and the energy left by 0.13 % of E0. Its tolerances are those, with the
//! peaks (set in the first periods, well-conditioned) at 2 %, and the impact count at 15 %.
//!
//! The compliant model is f64 and bitwise repeatable on one machine and build, but another
//! libm can flip one accept/reject decision of its adaptive steps: a perturbation at its
//! tolerance (1e-9 of the contact scales), which the paper scenes amplify as above. So it gets
//! the contact model's tolerances, and its peak contact force and true acceleration peak (set
//! by the fastest, earliest impacts) 2 %, like the peaks.
//!
//! A chaotic run amplifies round-off: a bed of balls that differs in the last bits of one
//! impact (another libm, or the same roots found from another instant) has another impact count
//! and other late-time metrics after a few seconds, though its early ones agree. So `--update`
//! measures how far each of the reference's values moves when the scene's restitution moves by
//! round-off's size (`PROBES` runs, each `e` moved by a further 1e-15 of itself), and keeps the
//! root mean square of those moves as the value's spread where `SPREAD_FACTOR` spreads exceed
//! the exact tolerance. The value's tolerance is then that many spreads: late-time values of a
//! chaotic scene are compared as members of their distribution, and every other value exactly
//! as before.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::StudyError;
use crate::metrics::{metrics, Headline, Metric, Metrics};
use crate::model::{Limits, Model, ModelError, RunOptions};
use crate::scene;
use crate::studies::chain::{run_chain, KerRow};
use crate::studies::sweep::sweep_scenes;

/// What is kept of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Golden {
    /// Case name (scene, sweep value or chain).
    pub case: String,
    /// Model name.
    pub model: Model,
    /// Impacts.
    pub impact_count: usize,
    /// Headline metrics.
    pub metrics: Option<Metrics>,
    /// KER rows, for a chain file.
    pub ker: Vec<KerRow>,
    /// When the model stopped the run with a typed stall (a state it has no rule for yet, such
    /// as the spatial reference's persistent contacts), s: the stop is the regression point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_at: Option<f64>,
    /// How far each value moves when the restitution moves by round-off's size (the root mean
    /// square of `PROBES` such runs), by the value's name; kept only where it widens the
    /// tolerance: the values of a chaotic run.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub spread: BTreeMap<String, f64>,
}

/// Runs with the restitution moved by round-off's size that a golden of the reference measures
/// its values' spread with.
const PROBES: usize = 8;

/// How far each probe moves the restitution from the last one, relative: about eight ulps.
const PROBE_STEP: f64 = 1e-15;

/// Spreads a value may move by in a check.
const SPREAD_FACTOR: f64 = 4.0;

/// One compared value.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Case name.
    pub case: String,
    /// Model name.
    pub model: Model,
    /// Metric name.
    pub metric: String,
    /// Golden value (`None`: no golden).
    pub golden: Option<f64>,
    /// Value now.
    pub now: Option<f64>,
    /// Allowed difference.
    pub tolerance: f64,
    /// Within tolerance.
    pub ok: bool,
}

/// Runs every case of every scene file in `dir` with every model; with `probe`, measures the
/// spread of the reference's values too (for `--update`); `progress` is called after each run.
pub fn current(dir: &Path, models: &[Model], probe: bool, progress: &(dyn Fn() + Sync)) -> Result<Vec<Golden>, StudyError> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| StudyError::Io { path: dir.display().to_string(), message: e.to_string() })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    let mut out = Vec::new();
    for path in paths {
        let loaded = scene::load(&path)?;
        let mut cases = Vec::new();
        if loaded.file.sweep.is_some() {
            cases.extend(sweep_scenes(&loaded)?.into_iter().map(|(_, s)| s));
        } else if let Some(s) = &loaded.scene {
            cases.push(s.clone());
        }
        for &model in models {
            // A model that cannot represent a scene has no golden for it: it says so up front.
            for s in cases.iter().filter(|s| model.supports(s).is_ok()) {
                let mut golden = run_case(s, model)?;
                if probe && model == Model::Reference {
                    golden.spread = spread(&golden, s, model)?;
                }
                progress();
                out.push(golden);
            }
            if let Some(chain) = &loaded.chain {
                let name = loaded.file.name.clone().unwrap_or_else(|| "chain".into());
                out.push(Golden {
                    case: name,
                    model,
                    impact_count: 0,
                    metrics: None,
                    ker: run_chain(chain, model, Limits::NONE, progress)?,
                    stopped_at: None,
                    spread: BTreeMap::new(),
                });
            }
        }
    }
    Ok(out)
}

/// What a golden keeps of one run of `scene` with `model`.
fn run_case(scene: &scene::Scene, model: Model) -> Result<Golden, StudyError> {
    let case = scene.name.clone();
    Ok(match model.simulate(scene, &RunOptions::default()) {
        Ok(run) => Golden {
            case,
            model,
            impact_count: run.impact_count(),
            metrics: Some(metrics(&run)),
            ker: vec![],
            stopped_at: None,
            spread: BTreeMap::new(),
        },
        Err(ModelError::Stalled { t, .. }) => {
            Golden { case, model, impact_count: 0, metrics: None, ker: vec![], stopped_at: Some(t), spread: BTreeMap::new() }
        }
        Err(e) => return Err(e.into()),
    })
}

/// The spread of each of `golden`'s values over `PROBES` runs of `scene` with the restitution
/// moved by round-off's size (towards the inside of [0, 1]; a plastic scene's not at all),
/// where it widens the value's tolerance. A value a probe does not have (a run that stops
/// where the golden's did not) is left out of that probe.
fn spread(golden: &Golden, scene: &scene::Scene, model: Model) -> Result<BTreeMap<String, f64>, StudyError> {
    let nominal = kept_values(golden);
    let mut squares = vec![(0.0, 0usize); nominal.len()];
    for k in 1..=PROBES {
        let step = k as f64 * PROBE_STEP * scene.restitution;
        let mut probe = scene.clone();
        probe.restitution = if scene.restitution + step <= 1.0 { scene.restitution + step } else { scene.restitution - step };
        let values = kept_values(&run_case(&probe, model)?);
        for ((sum, n), ((name, _, v0), (probe_name, _, v))) in squares.iter_mut().zip(nominal.iter().zip(&values)) {
            if let (true, Some(v0), Some(v)) = (name == probe_name, v0, v) {
                *sum += (v - v0).powi(2);
                *n += 1;
            }
        }
    }
    Ok(nominal
        .iter()
        .zip(squares)
        .filter(|(_, (_, n))| *n > 0)
        .filter_map(|((name, kind, v0), (sum, n))| {
            let rms = (sum / n as f64).sqrt();
            (SPREAD_FACTOR * rms > exact_tolerance(model, *kind, v0.unwrap_or(0.0))).then(|| (name.clone(), rms))
        })
        .collect())
}

/// Golden file of one case and model.
pub fn golden_path(golden_dir: &Path, case: &str, model: Model) -> PathBuf {
    let safe: String = case.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '.' { c } else { '_' }).collect();
    golden_dir.join(format!("{safe}.{model}.json"))
}

/// Reads the golden of `g`'s case and model, if any.
pub fn read_golden(golden_dir: &Path, g: &Golden) -> Result<Option<Golden>, StudyError> {
    let path = golden_path(golden_dir, &g.case, g.model);
    match std::fs::read(&path) {
        Ok(bytes) => serde_json::from_slice(&bytes)
            .map(Some)
            .map_err(|e| StudyError::Io { path: path.display().to_string(), message: e.to_string() }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(StudyError::Io { path: path.display().to_string(), message: e.to_string() }),
    }
}

/// The metrics a golden keeps of a damper scene's run, in report order.
const GOLDEN_METRICS: [Metric; 7] = [
    Metric::PeakDisplacement,
    Metric::PeakAcceleration,
    Metric::RmsDisplacement,
    Metric::SettlingTime,
    Metric::EnergyRemaining,
    Metric::PeakContactForce,
    Metric::PeakTrueAcceleration,
];

/// How far a value of one metric may move from `golden` without a spread: the larger of the
/// model's absolute tolerance and its relative one of `golden`.
fn exact_tolerance(model: Model, metric: Option<Metric>, golden: f64) -> f64 {
    let (rel, abs) = tolerance(model, metric);
    abs.max(rel * golden.abs())
}

/// Tolerance of one metric (`None`: a KER row) for a model: `(relative, absolute)`.
fn tolerance(model: Model, metric: Option<Metric>) -> (f64, f64) {
    if model == Model::Reference {
        return if metric == Some(Metric::ImpactCount) { (0.0, 0.0) } else { (1e-9, 1e-15) };
    }
    match metric {
        Some(Metric::PeakDisplacement | Metric::PeakAcceleration | Metric::PeakContactForce | Metric::PeakTrueAcceleration) => (0.02, 0.0),
        Some(Metric::RmsDisplacement) => (0.0, 0.5e-3),
        Some(Metric::SettlingTime) => (0.0, 0.8),
        Some(Metric::EnergyRemaining) => (0.0, 1.3e-3),
        Some(Metric::ImpactCount) => (0.15, 1.0),
        _ => (0.0, 0.01), // KER
    }
}

/// A golden's values in report order: their names, their metrics (`None`: a KER row or the
/// time a run stopped) and the values.
fn kept_values(g: &Golden) -> Vec<(String, Option<Metric>, Option<f64>)> {
    let mut v = vec![(Metric::ImpactCount.name().to_string(), Some(Metric::ImpactCount), Some(g.impact_count as f64))];
    if let Some(metrics) = g.metrics {
        // A golden keeps no impact totals: only the metrics read here.
        let headline = Headline { metrics, impact_count: g.impact_count, impact_loss: f64::NAN, impact_rate: f64::NAN };
        v.extend(GOLDEN_METRICS.iter().map(|&m| (m.name().to_string(), Some(m), headline.value(m))));
    }
    for r in &g.ker {
        v.push((format!("ker {}L-{}S", r.large, r.small), None, Some(r.ker)));
    }
    if let Some(t) = g.stopped_at {
        v.push(("stopped at (s)".to_string(), None, Some(t)));
    }
    v
}

/// Compares `now` with `golden` value by value: within the model's tolerance, or within
/// `SPREAD_FACTOR` of the golden's spread of the value where that is wider.
pub fn compare(now: &Golden, golden: Option<&Golden>) -> Vec<Row> {
    let now_values = kept_values(now);
    let golden_values = golden.map(kept_values);
    now_values
        .into_iter()
        .enumerate()
        .map(|(i, (metric, kind, value))| {
            let g = golden_values.as_ref().and_then(|gv| gv.get(i).filter(|(m, ..)| *m == metric).map(|(.., v)| *v));
            let spread = golden.and_then(|g| g.spread.get(&metric)).map_or(0.0, |s| SPREAD_FACTOR * s);
            let allowed = |gv: f64| exact_tolerance(now.model, kind, gv).max(spread);
            let (golden, ok, tol) = match (g, value) {
                (None, _) => (None, false, allowed(0.0)),
                (Some(None), None) => (None, true, allowed(0.0)),
                (Some(Some(gv)), Some(v)) => {
                    let tol = allowed(gv);
                    (Some(gv), (v - gv).abs() <= tol, tol)
                }
                (Some(gv), _) => (gv, false, allowed(0.0)),
            };
            Row { case: now.case.clone(), model: now.model, metric, golden, now: value, tolerance: tol, ok }
        })
        .collect()
}

/// Writes `g` as its golden file.
pub fn write_golden(golden_dir: &Path, g: &Golden) -> Result<(), StudyError> {
    let path = golden_path(golden_dir, &g.case, g.model);
    let bytes = serde_json::to_vec_pretty(g).expect("serialises");
    crate::files::write_atomic(&path, &bytes).map_err(|e| StudyError::Io { path: path.display().to_string(), message: e.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn golden(impact_count: usize, spread: &[(&str, f64)]) -> Golden {
        Golden {
            case: "bed".into(),
            model: Model::Reference,
            impact_count,
            metrics: None,
            ker: vec![],
            stopped_at: None,
            spread: spread.iter().map(|&(name, s)| (name.to_string(), s)).collect(),
        }
    }

    /// A value with a spread may move by `SPREAD_FACTOR` spreads and no more; without one the
    /// reference's impact count is held exactly.
    #[test]
    fn a_spread_widens_its_own_value_alone() {
        let kept = golden(1000, &[(Metric::ImpactCount.name(), 10.0)]);
        let ok = |now: usize, g: &Golden| compare(&golden(now, &[]), Some(g)).iter().all(|r| r.ok);
        assert!(ok(1040, &kept) && ok(960, &kept));
        assert!(!ok(1041, &kept) && !ok(959, &kept));
        let exact = golden(1000, &[]);
        assert!(ok(1000, &exact) && !ok(1001, &exact));
        // A spread of another value leaves the count exact.
        assert!(!ok(1001, &golden(1000, &[(Metric::SettlingTime.name(), 10.0)])));
    }
}
