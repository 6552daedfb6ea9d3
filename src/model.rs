//! The models behind one interface: anything that turns a [`Scene`] into a [`Run`].

use crate::run::Run;
use crate::scene::Scene;

/// A model of the damper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Model {
    /// The exact event-driven impulse solver.
    Reference,
    /// Rapier colliders in a headless Bevy app.
    Rapier,
    /// Hertz contacts with Hunt-Crossley damping, integrated through every contact.
    Compliant,
}

impl Model {
    /// Every model, in report order.
    pub const ALL: &'static [Model] = &[Model::Reference, Model::Rapier, Model::Compliant];

    /// Name used on the command line and in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Model::Reference => "reference",
            Model::Rapier => "rapier",
            Model::Compliant => "compliant",
        }
    }

    /// Runs the model on `scene`.
    pub fn simulate(self, scene: &Scene) -> Result<Run, ModelError> {
        match self {
            Model::Reference => Ok(crate::reference::simulate(scene)?),
            Model::Rapier => crate::rapier::simulate(scene),
            Model::Compliant => Ok(crate::compliant::simulate(scene)?),
        }
    }
}

impl std::str::FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Model::ALL
            .iter()
            .copied()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown model `{s}`; choose one of {}", Model::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ")))
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
