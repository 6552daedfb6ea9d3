//! The chain experiment of docs/MODEL.md §8: an incident ball strikes a chain of balls at rest; the
//! kinetic energy ratio `KER = KE of all balls after / KE of the incident ball before`.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::model::{Limits, Model, ModelError, RunOptions};
use crate::run::Run;
use crate::scene::{ChainCase, Scene};

/// One row of the KER table (the JSON contract of `lpc chain`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KerRow {
    /// `N_L`.
    pub large: u32,
    /// Number of small balls (`N_L - 1` or 0).
    pub small: u32,
    /// Kinetic energy ratio.
    pub ker: f64,
}

/// KER of a finished chain run.
pub fn ker(scene: &Scene, run: &Run) -> f64 {
    let after: f64 = scene.balls.iter().zip(&run.final_velocities).map(|(b, v)| 0.5 * b.mass * v * v).sum();
    after / scene.initial_energy()
}

/// Runs every case with `model`, in parallel, each within `limits`; `progress` is called after
/// each.
pub fn run_chain(cases: &[ChainCase], model: Model, limits: Limits, progress: &(dyn Fn() + Sync)) -> Result<Vec<KerRow>, ModelError> {
    cases
        .par_iter()
        .map(|c| {
            let run = model.simulate(&c.scene, &RunOptions::limited(limits));
            progress();
            let run = run?;
            Ok(KerRow { large: c.large, small: if c.small { c.large - 1 } else { 0 }, ker: ker(&c.scene, &run) })
        })
        .collect()
}
