//! The models behind one interface: [`Model::simulate`] turns a [`Scene`] into a [`Run`]
//! (the label [`Model`] itself lives with the outputs in `run`, which every model writes).

pub use crate::run::Model;
use crate::run::{Record, Run};
use crate::scene::Scene;

impl Model {
    /// Runs the model on `scene`, after checking that its series fit in memory.
    pub fn simulate(self, scene: &Scene) -> Result<Run, ModelError> {
        self.simulate_recording(scene, Record::Series)
    }

    /// Runs the model on `scene`, keeping what `record` asks for (the series are checked
    /// against the memory left only when kept).
    pub fn simulate_recording(self, scene: &Scene, record: Record) -> Result<Run, ModelError> {
        self.simulate_within(scene, record, None)
    }

    /// [`Model::simulate_recording`] within `max_wall_s` seconds of computing, if given: a run
    /// that takes longer stops with a typed error (each model's `OverBudget`).
    pub fn simulate_within(self, scene: &Scene, record: Record, max_wall_s: Option<f64>) -> Result<Run, ModelError> {
        if record == Record::Series {
            crate::run::check_memory(scene).map_err(ModelError::Refused)?;
        }
        match self {
            Model::Reference => Ok(crate::reference::simulate_within(scene, record, max_wall_s)?),
            Model::Rapier => crate::rapier::simulate_within(scene, record, max_wall_s),
            Model::Compliant => {
                let options = crate::compliant::Options { record, max_wall_s, ..Default::default() };
                Ok(crate::compliant::simulate_with(scene, options)?)
            }
        }
    }
}

/// A model could not complete a run.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The reference stalled.
    #[error(transparent)]
    Reference(#[from] crate::reference::ReferenceError),
    /// The compliant model stalled.
    #[error(transparent)]
    Compliant(#[from] crate::compliant::CompliantError),
    /// The model refuses this scene (with the reason).
    #[error("{0}")]
    Refused(String),
    /// The model found during the run that it cannot resolve the scene (with the reason)
    /// and stopped rather than return a wrong run.
    #[error("{0}")]
    Unstable(String),
    /// The contact model ran out of its computing-time budget (with where it stood).
    #[error("{0}")]
    OverBudget(String),
}
