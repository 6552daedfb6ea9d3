//! Design search (`lpc optimize`): the damper with the shortest settling time, or the lowest
//! resonant amplitude, among arrangements and parameter ranges, inside a given container.
//!
//! The objective of an impact damper is not smooth in its parameters (a small change of
//! clearance can add or remove an impact sequence; docs/BENCHMARKS.md, "Sensitivity"), so the
//! search is a grid, not a gradient method: every arrangement over the full grid of the
//! axes, then [`REFINE_POINTS`] points per axis between the best point's neighbours, repeated
//! `refinements` times. Every evaluation is kept, so the ranking shows how flat the optimum is.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::StudyError;
use crate::model::{Limits, Model, RunOptions};
use crate::scene::{self, Arrangement, Length, Loaded, Parameter, Scene, SceneError};
use crate::studies::ensemble;
use crate::studies::frf;
use crate::studies::sweep::Axis;

/// Points per axis in each refinement.
pub const REFINE_POINTS: usize = 5;

/// What to minimise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Objective {
    /// `settling_time` of the free-vibration scene (an unsettled run is worst).
    SettlingTime,
    /// Largest steady amplitude over `steps` forcing frequencies from `from` to `to` Hz.
    ResonantAmplitude {
        /// Hz.
        from: f64,
        /// Hz.
        to: f64,
        /// Frequencies.
        steps: usize,
    },
}

/// One evaluated design.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Design {
    /// Ball arrangement, e.g. `LSL`.
    pub arrangement: String,
    /// `(parameter, value as written)` of each axis.
    pub values: Vec<(String, f64)>,
    /// Clearance that follows from the container length, m.
    pub clearance: f64,
    /// Objective (s or m); `None` when not settled. Over an ensemble: the chosen quantile of
    /// the members' objectives (a member that never settled counts as infinitely long).
    pub objective: Option<f64>,
    /// Over an ensemble: the 5-95 % band of that quantile by bootstrap (given for the best
    /// design and the runner-up).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band: Option<(f64, f64)>,
    /// Over an ensemble: each member's objective (infinite when not settled).
    #[serde(skip)]
    pub member_objectives: Vec<f64>,
}

/// The outcome of a search.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Search {
    /// The best design.
    pub best: Option<Design>,
    /// Every feasible design evaluated, best first.
    pub ranking: Vec<Design>,
    /// Designs whose balls do not fit the container (or are otherwise invalid).
    pub infeasible: usize,
    /// Over an ensemble: whether the best design is told apart from the runner-up (their
    /// bootstrap bands do not overlap); `null` without an ensemble or a runner-up.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distinguishable: Option<bool>,
}

/// Designs judged over ensembles: every design's members drawn under the scene's
/// `[tolerances]`, ranked by a quantile of their objectives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Robust {
    /// Members per design.
    pub members: usize,
    /// Seed of the draws (default: the scene's).
    pub seed: Option<u64>,
    /// The quantile ranked by.
    pub quantile: f64,
}

/// How designs are judged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Judging {
    /// What is minimised.
    pub objective: Objective,
    /// The model that runs each design.
    pub model: Model,
    /// What each run may cost.
    pub limits: Limits,
    /// Refinements around the best grid point.
    pub refinements: u32,
    /// Over ensembles (ranked by a quantile), or one run per design.
    pub robust: Option<Robust>,
}

/// Searches `arrangements` x the grid of `axes` (refined `judging.refinements` times) for the
/// design minimising `judging.objective`, with the container's inner length fixed to
/// `container_length`.
pub fn optimize(
    loaded: &Loaded,
    axes: &[Axis],
    arrangements: &[String],
    container_length: Length,
    judging: Judging,
    progress: &(dyn Fn() + Sync),
) -> Result<Search, StudyError> {
    let Judging { objective, refinements, robust, .. } = judging;
    let invalid = |field: &str, rule: String| SceneError::Invalid { file: loaded.path.clone(), field: field.into(), rule };
    if axes.iter().any(|a| a.parameter == Parameter::Clearance) {
        return Err(invalid("clearance", "follows from the container length here: vary gap, mass_ratio, ... instead".into()).into());
    }
    if matches!(objective, Objective::ResonantAmplitude { .. }) && loaded.file.forcing.is_none() {
        return Err(invalid("forcing", "is missing: the resonant amplitude needs a [forcing] table".into()).into());
    }
    let mut base = loaded.file.clone();
    base.sweep = None;
    {
        let balls = base.balls.as_mut().ok_or_else(|| invalid("balls", "is missing: a design needs [balls]".into()))?;
        balls.clearance = None;
        balls.container_length = Some(container_length);
    }
    let mut infeasible = 0;
    let mut all: Vec<Design> = Vec::new();
    for arrangement in arrangements {
        let mut file = base.clone();
        file.balls.as_mut().expect("checked").arrangement = Arrangement::Letters(arrangement.clone());
        let mut grid: Vec<Vec<Length>> = axes.iter().map(|a| a.values.clone()).collect();
        for pass in 0..=refinements {
            let (designs, bad) = evaluate(loaded, &file, arrangement, axes, &grid, judging, progress)?;
            infeasible += bad;
            let best = designs.iter().filter(|d| d.objective.is_some()).min_by(|a, b| cmp(a, b)).cloned();
            all.extend(designs);
            let Some(best) = best else { break };
            if pass == refinements {
                break;
            }
            // Refine between the best point's neighbours on each axis.
            grid = grid
                .iter()
                .zip(&best.values)
                .zip(axes)
                .map(|((values, (_, v)), axis)| {
                    let k = values.iter().position(|x| x.raw() == *v).unwrap_or(0);
                    let lo = values[k.saturating_sub(1)];
                    let hi = values[(k + 1).min(values.len() - 1)];
                    // A count (the number of chains) is refined over the whole numbers between.
                    if axis.parameter.is_count() {
                        return (lo.raw().round() as i64..=hi.raw().round() as i64).map(|c| Length::Metres(c as f64)).collect();
                    }
                    (0..REFINE_POINTS)
                        .map(|i| {
                            let x = crate::studies::sweep::tidy(lo.raw() + (hi.raw() - lo.raw()) * i as f64 / (REFINE_POINTS - 1) as f64);
                            match lo {
                                Length::Metres(_) => Length::Metres(x),
                                Length::Rr(_) => Length::Rr(x),
                            }
                        })
                        .collect()
                })
                .collect();
        }
    }
    // Refinements revisit grid points (up to round-off in their values): keep each design once.
    let same = |a: &Design, b: &Design| {
        a.arrangement == b.arrangement
            && a.values.iter().zip(&b.values).all(|((_, x), (_, y))| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()))
    };
    all.sort_by(|a, b| {
        cmp(a, b)
            .then_with(|| a.arrangement.cmp(&b.arrangement))
            .then_with(|| a.values.iter().map(|v| v.1).partial_cmp(b.values.iter().map(|v| v.1)).unwrap_or(std::cmp::Ordering::Equal))
    });
    all.dedup_by(|a, b| same(a, b));
    let mut distinguishable = None;
    if let Some(r) = robust {
        let seed = r.seed.unwrap_or(ensemble::DEFAULT_SEED);
        for d in all.iter_mut().take(2).filter(|d| d.objective.is_some()) {
            d.band = ensemble::bootstrap_band(&d.member_objectives, r.quantile, seed);
        }
        if let [Some((_, best_hi)), Some((runner_lo, _))] = [all.first().and_then(|d| d.band), all.get(1).and_then(|d| d.band)] {
            distinguishable = Some(best_hi < runner_lo);
        }
    }
    Ok(Search { best: all.first().filter(|d| d.objective.is_some()).cloned(), ranking: all, infeasible, distinguishable })
}

/// Lower objective first; unsettled last.
fn cmp(a: &Design, b: &Design) -> std::cmp::Ordering {
    let key = |d: &Design| d.objective.unwrap_or(f64::INFINITY);
    key(a).total_cmp(&key(b))
}

#[allow(clippy::too_many_arguments)]
fn evaluate(
    loaded: &Loaded,
    file: &scene::SceneFile,
    arrangement: &str,
    axes: &[Axis],
    grid: &[Vec<Length>],
    judging: Judging,
    progress: &(dyn Fn() + Sync),
) -> Result<(Vec<Design>, usize), StudyError> {
    let Judging { objective, model, limits, robust, .. } = judging;
    let mut points: Vec<Vec<Length>> = vec![vec![]];
    for values in grid {
        points = points.iter().flat_map(|p| values.iter().map(move |v| [p.clone(), vec![*v]].concat())).collect();
    }
    let name = loaded.scene.as_ref().map_or(String::new(), |s| s.name.clone());
    let results: Vec<Option<Design>> = points
        .par_iter()
        .map(|point| {
            let mut f = file.clone();
            for (axis, value) in axes.iter().zip(point) {
                f = axis.parameter.apply(&f, *value).map_err(|rule| SceneError::Invalid {
                    file: loaded.path.clone(),
                    field: axis.parameter.to_string(),
                    rule,
                })?;
            }
            // A design whose balls do not fit is infeasible, not an error.
            let Ok(valid) = scene::from_file(f.clone(), &loaded.path, &name) else {
                progress();
                return Ok(None);
            };
            let Some(scene) = valid.scene else {
                progress();
                return Ok(None);
            };
            let objective_of = |scene: &Scene| -> Result<Option<f64>, StudyError> {
                Ok(match objective {
                    Objective::SettlingTime => {
                        crate::metrics::metrics(&model.simulate(scene, &RunOptions { limits, ..RunOptions::metrics_only() })?).settling_time
                    }
                    Objective::ResonantAmplitude { from, to, steps } => {
                        let mut worst: f64 = 0.0;
                        for f in frf::frequencies(from, to, steps) {
                            let (reading, _) = frf::steady_run(&frf::forced_at(scene, f), model, limits)?;
                            worst = worst.max(reading.amplitude);
                        }
                        Some(worst)
                    }
                })
            };
            let (value, member_objectives) = match robust {
                None => (objective_of(&scene)?, vec![]),
                Some(r) => {
                    let members = ensemble::draw(&f, &loaded.path, &scene, loaded.tolerances.as_ref(), r.members, r.seed)?;
                    let values = ensemble::map_members(&members.members, |m| objective_of(&m.scene), &|| {})?;
                    let mut values: Vec<f64> = values.into_iter().map(|v| v.unwrap_or(f64::INFINITY)).collect();
                    let mut sorted = values.clone();
                    sorted.sort_by(f64::total_cmp);
                    let q = ensemble::quantile(&sorted, r.quantile);
                    values.shrink_to_fit();
                    (q.is_finite().then_some(q), values)
                }
            };
            progress();
            Ok(Some(Design {
                arrangement: arrangement.to_string(),
                values: axes.iter().zip(point).map(|(a, v)| (a.parameter.to_string(), v.raw())).collect(),
                clearance: scene.container.map_or(0.0, |c| c.clearance),
                objective: value,
                band: None,
                member_objectives,
            }))
        })
        .collect::<Result<_, StudyError>>()?;
    let infeasible = results.iter().filter(|r| r.is_none()).count();
    Ok((results.into_iter().flatten().collect(), infeasible))
}
