//! The models behind one interface: [`Model::simulate`] turns a [`Scene`] into a [`Run`]
//! (the label [`Model`] itself lives with the outputs in `run`, which every model writes).

pub use crate::run::Model;
use crate::run::Run;
use crate::scene::Scene;

impl Model {
    /// Runs the model on `scene`, after checking that its series fit in memory.
    pub fn simulate(self, scene: &Scene) -> Result<Run, ModelError> {
        crate::run::check_memory(scene).map_err(ModelError::Refused)?;
        match self {
            Model::Reference => Ok(crate::reference::simulate(scene)?),
            Model::Rapier => crate::rapier::simulate(scene),
            Model::Compliant => Ok(crate::compliant::simulate(scene)?),
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
}
