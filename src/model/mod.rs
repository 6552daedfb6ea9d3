//! What a model is to the rest of the tool: something that says whether it can represent a
//! scene, turns a scene into a [`Run`] under [`RunOptions`], stops with a typed [`ModelError`],
//! and states the tolerances its results are checked with ([`Checks`]). The models
//! (`reference`, `rapier`, `compliant`) each implement [`Simulator`] in their own folder and
//! never import each other; `registry` lists them.

pub mod cost;
mod error;
mod options;

pub use crate::run::Model;
pub use error::{ModelError, OverBudget};
pub use options::{Budget, Limits, Meter, Progress, RunOptions};

use crate::run::Run;
use crate::scene::Scene;

/// A model of the damper.
pub trait Simulator: Sync {
    /// Which model this is.
    fn model(&self) -> Model;

    /// Whether the model can represent `scene`: the reason when it cannot. Asked before any
    /// work, so that a scene a model cannot run is refused up front, never run wrongly.
    fn supports(&self, scene: &Scene) -> Result<(), String>;

    /// Runs the model on a scene it supports. The caller has checked the budgets and that the
    /// series fits in memory ([`Model::simulate`](crate::run::Model) does both).
    fn simulate(&self, scene: &Scene, options: &RunOptions) -> Result<Run, ModelError>;

    /// The tolerances a run of `scene` by this model is checked with.
    fn checks(&self, scene: &Scene, run: &Run) -> Checks;

    /// The scene settings the model reads, so that a study varies only those.
    fn settings(&self) -> &'static [Setting];

    /// How the model steps on `scene` (`event-driven`, `aligned`, `fixed`, `adaptive`).
    fn stepping(&self, scene: &Scene) -> &'static str;
}

/// A setting of a scene that some model reads (`[rapier]` and `[compliant]` tables, and the
/// command line's flags for them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Setting {
    /// How steps are chosen (`rapier.stepping`).
    Stepping,
    /// The (longest) step (`rapier.dt`).
    Dt,
    /// Solver iterations per step (`rapier.solver_iterations`).
    SolverIterations,
    /// The error tolerance of an adaptive integration (`compliant.tolerance`).
    Tolerance,
}

/// The tolerances a model's run is checked with (`lpc stress`, and every test that judges a
/// run): what its arithmetic allows, stated by the model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Checks {
    /// Energy the system may hold beyond what was put in, relative to it.
    pub energy_gain: f64,
    /// How closely the energy balance closes, relative to the energies that flow; `None` for a
    /// model that keeps no balance.
    pub balance: Option<f64>,
    /// Energy an impact may appear to gain, relative to the energy put in (the initial energy
    /// and the excitation's work).
    pub impact_gain: f64,
    /// Whether each single impact loses at most what Eq. 9-10 can take (exact impulses).
    pub exact_impacts: bool,
    /// Drift of the total momentum of a free frame and its balls, relative to its scale.
    pub momentum: f64,
    /// How far a ball may lie outside its container, m.
    pub wall_overlap: f64,
    /// How far two balls may overlap, m; `None` for a model whose balls deform (bounded by
    /// `wall_overlap` already).
    pub ball_overlap: Option<f64>,
    /// Most events or steps per simulated second before the run counts as stalled; `None` for
    /// a model whose steps follow its contacts (it guards against stalling with its step
    /// budget instead).
    pub stall_rate: Option<f64>,
}

/// Most events (reference) or steps (Rapier) per simulated second before a run counts as
/// stalled. The densest valid scenes on lines reach a few 10^5 (see docs/BENCHMARKS.md).
pub const STALL_EVENTS_PER_SIM_S: f64 = 2e6;
