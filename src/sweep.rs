//! Parameter sweeps: one scene file, one `[sweep]` parameter, every value run in parallel.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::model::{Model, ModelError};
use crate::output::RunSummary;
use crate::scene::{self, Loaded, Scene, SceneError};

/// One value of a sweep (the JSON contract of `lpc sweep`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepPoint {
    /// Parameter name.
    pub parameter: String,
    /// Its value as written in the file (metres or Rr multiples for lengths).
    pub value: f64,
    /// The run.
    pub summary: RunSummary,
}

/// The scenes of a sweep, one per value, each validated.
pub fn sweep_scenes(loaded: &Loaded) -> Result<Vec<(f64, Scene)>, SceneError> {
    let sweep = loaded.file.sweep.as_ref().ok_or_else(|| SceneError::Invalid {
        file: loaded.path.clone(),
        field: "sweep".into(),
        rule: "is missing: this command needs a scene file with a [sweep] table".into(),
    })?;
    let base = loaded.scene.as_ref().map(|s| s.name.clone()).unwrap_or_default();
    sweep
        .values
        .iter()
        .map(|value| {
            let file = scene::apply_sweep_value(&loaded.file, &sweep.parameter, *value).map_err(|rule| {
                SceneError::Invalid { file: loaded.path.clone(), field: "sweep.parameter".into(), rule }
            })?;
            let mut s = scene::from_file(file, &loaded.path, &base)?.scene.expect("damper scene");
            s.name = format!("{base}[{}={}]", sweep.parameter, value.raw());
            Ok((value.raw(), s))
        })
        .collect()
}

/// Runs every scene with `model` in parallel; `progress` is called after each run.
pub fn run_sweep(
    parameter: &str,
    scenes: &[(f64, Scene)],
    model: Model,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<SweepPoint>, ModelError> {
    scenes
        .par_iter()
        .map(|(value, scene)| {
            let run = model.simulate(scene)?;
            progress();
            Ok(SweepPoint { parameter: parameter.to_string(), value: *value, summary: RunSummary::of(&run) })
        })
        .collect()
}
