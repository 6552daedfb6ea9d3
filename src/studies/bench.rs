//! Run time against error: every model and setting (Rapier's stepping, step and iterations;
//! the compliant model's error tolerance) on every scene, the median computing time
//! per simulated second over repeated runs, `lpc compare`'s errors, and the Pareto front.

use serde::{Deserialize, Serialize};

use super::StudyError;
use crate::model::{Model, RunOptions, Setting};
use crate::scene::{Overrides, Scene, Stepping};
use crate::studies::compare::{errors, Errors};

/// A setting of a model (all `None` for the reference, which has none).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// `"fixed"`, `"aligned"`, or `"event-driven"` for the reference.
    pub stepping: &'static str,
    /// Step (longest step when aligned), s.
    pub dt: Option<f64>,
    /// Solver iterations.
    pub solver_iterations: Option<u32>,
    /// Error tolerance (compliant model).
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// One measured setting (the JSON contract of `lpc bench`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchRow {
    /// Scene name.
    pub scene: String,
    /// Model name.
    pub model: Model,
    /// The setting.
    pub settings: Settings,
    /// Median computing time per simulated second.
    pub wall_s_per_sim_s: f64,
    /// Errors against the reference (zero for the reference itself).
    pub errors: Errors,
    /// Physics steps (Rapier) or events (reference) per simulated second.
    pub steps_per_sim_s: f64,
    /// No other setting of this scene is both cheaper and more accurate (early error).
    pub pareto: bool,
}

/// What to measure.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Models.
    pub models: Vec<Model>,
    /// Steppings, for models that read one.
    pub steppings: Vec<Stepping>,
    /// Steps, for models that read one.
    pub dts: Vec<f64>,
    /// Solver iterations, for models that read them.
    pub solver_iterations: Vec<u32>,
    /// Error tolerances, for models that read one.
    pub tolerances: Vec<f64>,
    /// Runs per setting (the median is kept).
    pub repeat: usize,
}

impl Plan {
    /// The settings `model` is measured at: every combination of the values given for the
    /// settings it reads (one, with none, for a model that reads none).
    pub fn variants(&self, model: Model) -> Vec<Overrides> {
        let mut variants = vec![Overrides::default()];
        for setting in model.settings() {
            variants = variants
                .into_iter()
                .flat_map(|v| -> Vec<Overrides> {
                    match setting {
                        Setting::Stepping => self.steppings.iter().map(|&x| Overrides { stepping: Some(x), ..v }).collect(),
                        Setting::Dt => self.dts.iter().map(|&x| Overrides { dt: Some(x), ..v }).collect(),
                        Setting::SolverIterations => {
                            self.solver_iterations.iter().map(|&x| Overrides { solver_iterations: Some(x), ..v }).collect()
                        }
                        Setting::Tolerance => self.tolerances.iter().map(|&x| Overrides { tolerance: Some(x), ..v }).collect(),
                    }
                })
                .collect();
        }
        variants
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Measures every setting of `plan` on `scene` (sequentially, so timings do not compete);
/// `progress` is called after each setting.
pub fn bench_scene(scene: &Scene, plan: &Plan, progress: &dyn Fn()) -> Result<Vec<BenchRow>, StudyError> {
    let defaults = RunOptions::default();
    let reference = Model::Reference.simulate(scene, &defaults)?;
    let mut rows = Vec::new();
    for &model in &plan.models {
        for variant in plan.variants(model) {
            let s = variant.apply(scene.clone(), "(command line)")?;
            let mut times = Vec::with_capacity(plan.repeat);
            let mut last = None;
            for _ in 0..plan.repeat.max(1) {
                let run = model.simulate(&s, &defaults)?;
                times.push(run.wall_time_s);
                last = Some(run);
            }
            let run = last.expect("at least one run");
            rows.push(BenchRow {
                scene: scene.name.clone(),
                model,
                settings: Settings {
                    stepping: model.stepping(&s),
                    dt: variant.dt,
                    solver_iterations: variant.solver_iterations,
                    tolerance: variant.tolerance,
                },
                wall_s_per_sim_s: median(times) / s.horizon,
                errors: errors(&run, &reference),
                steps_per_sim_s: run.events as f64 / s.horizon,
                pareto: false,
            });
            progress();
        }
    }
    mark_pareto(&mut rows);
    Ok(rows)
}

/// Marks the rows that no other setting of the same scene and model dominates in
/// (cost, early error). (Across models the exact reference would dominate everything.)
pub fn mark_pareto(rows: &mut [BenchRow]) {
    let key: Vec<(&str, Model, f64, f64)> =
        rows.iter().map(|r| (r.scene.as_str(), r.model, r.wall_s_per_sim_s, r.errors.max_xs_early)).collect();
    let front: Vec<bool> = key
        .iter()
        .enumerate()
        .map(|(i, &(s, m, c, e))| {
            !key.iter().enumerate().any(|(j, &(sj, mj, cj, ej))| j != i && sj == s && mj == m && cj <= c && ej <= e && (cj < c || ej < e))
        })
        .collect();
    for (row, f) in rows.iter_mut().zip(front) {
        row.pareto = f;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(cost: f64, err: f64) -> BenchRow {
        BenchRow {
            scene: "s".into(),
            model: Model::Rapier,
            settings: Settings { stepping: "fixed", dt: None, solver_iterations: None, tolerance: None },
            wall_s_per_sim_s: cost,
            errors: Errors { rms_xs: 0.0, max_xs_early: err, settling_time_diff: None, impact_loss_diff: 0.0, impact_count_diff: 0 },
            steps_per_sim_s: 0.0,
            pareto: false,
        }
    }

    #[test]
    fn pareto_front_keeps_only_undominated_settings() {
        let mut rows = vec![row(1.0, 1.0), row(2.0, 0.5), row(3.0, 0.6), row(0.5, 2.0), row(2.0, 0.5)];
        mark_pareto(&mut rows);
        let front: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        // (3, 0.6) is dominated by (2, 0.5); the two equal (2, 0.5) do not dominate each other.
        assert_eq!(front, vec![true, true, false, true, true]);
    }
}
