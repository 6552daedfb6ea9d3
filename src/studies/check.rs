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
}

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

/// Runs every case of every scene file in `dir` with every model; `progress` is called after
/// each run.
pub fn current(dir: &Path, models: &[Model], progress: &(dyn Fn() + Sync)) -> Result<Vec<Golden>, StudyError> {
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
                let golden = match model.simulate(s, &RunOptions::default()) {
                    Ok(run) => Golden {
                        case: s.name.clone(),
                        model,
                        impact_count: run.impacts.len(),
                        metrics: Some(metrics(&run)),
                        ker: vec![],
                        stopped_at: None,
                    },
                    Err(ModelError::Stalled { t, .. }) => {
                        Golden { case: s.name.clone(), model, impact_count: 0, metrics: None, ker: vec![], stopped_at: Some(t) }
                    }
                    Err(e) => return Err(e.into()),
                };
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
                });
            }
        }
    }
    Ok(out)
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

/// Compares `now` with `golden` metric by metric.
pub fn compare(now: &Golden, golden: Option<&Golden>) -> Vec<Row> {
    let values = |g: &Golden| -> Vec<(String, Option<Metric>, Option<f64>)> {
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
    };
    let now_values = values(now);
    let golden_values = golden.map(values);
    now_values
        .into_iter()
        .enumerate()
        .map(|(i, (metric, kind, value))| {
            let g = golden_values.as_ref().and_then(|gv| gv.get(i).filter(|(m, ..)| *m == metric).map(|(.., v)| *v));
            let (rel, abs) = tolerance(now.model, kind);
            let (golden, ok, tol) = match (g, value) {
                (None, _) => (None, false, abs),
                (Some(None), None) => (None, true, abs),
                (Some(Some(gv)), Some(v)) => {
                    let tol = abs.max(rel * gv.abs());
                    (Some(gv), (v - gv).abs() <= tol, tol)
                }
                (Some(gv), _) => (gv, false, abs),
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
