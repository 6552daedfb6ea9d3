//! Why a model did not return a finished run: one typed reason for every model, so that a study
//! or a command decides what a stop means by its kind, never by its words.

use super::options::Budget;
use crate::run::{Model, Run};
use crate::scene::human;

/// A model did not return a finished run.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The model cannot run this scene as it stands, said before any work: the reason (a
    /// scene it cannot represent, a series that would not fit in memory).
    #[error("{0}")]
    Refused(String),
    /// A budget ran out before the horizon; the run so far is kept.
    #[error(transparent)]
    OverBudget(Box<OverBudget>),
    /// The run would not reach its horizon: events piled up at one instant, or a step fell to
    /// round-off.
    #[error("scene `{scene}`: {} stalled after {steps} {} at t = {} s: {why}", .model.title(), .model.step_unit(), human(*.t))]
    Stalled {
        /// Scene name.
        scene: String,
        /// The model.
        model: Model,
        /// Simulated time reached, s.
        t: f64,
        /// Steps or events taken.
        steps: u64,
        /// Which limit was reached.
        why: String,
    },
    /// The model found during the run that it cannot resolve the scene, and stopped rather
    /// than return a wrong run.
    #[error("scene `{scene}`: {} stopped: {reason}", .model.title())]
    Unstable {
        /// Scene name.
        scene: String,
        /// The model.
        model: Model,
        /// Simulated time reached, s.
        t: f64,
        /// What it could not resolve, and where.
        reason: String,
    },
    /// An invariant the model guarantees broke: a bug of the model, which stops rather than go
    /// on with a wrong run.
    #[error("scene `{scene}`: {} broke {what}; this is a bug of the {model}, please report it with the scene file", .model.title())]
    Broken {
        /// Scene name.
        scene: String,
        /// The model.
        model: Model,
        /// Simulated time, s.
        t: f64,
        /// The invariant, where and by how much.
        what: String,
    },
}

/// A run stopped by its budget, with what its steps cost and the run so far.
#[derive(Debug, thiserror::Error)]
#[error(
    "scene `{scene}`: {} stopped at t = {} s of {} s after {steps} {} and {wall_s:.1} s of computing: {}; {cost}",
    .model.title(), human(*.t), human(*.horizon), .model.step_unit(), self.budget_text()
)]
pub struct OverBudget {
    /// Scene name.
    pub scene: String,
    /// The model.
    pub model: Model,
    /// Simulated time reached, s.
    pub t: f64,
    /// The scene's horizon, s.
    pub horizon: f64,
    /// Steps (or events) taken.
    pub steps: u64,
    /// Computing time, s.
    pub wall_s: f64,
    /// Which budget ran out.
    pub budget: Budget,
    /// Its limit, in its unit.
    pub limit: f64,
    /// What the steps cost (the model's own account: the open contacts, the impacts so far).
    pub cost: String,
    /// The run up to `t` (series, impacts, energy account so far).
    pub partial: Run,
}

impl OverBudget {
    /// `more than 3000 steps (--max-steps)`.
    pub fn budget_text(&self) -> String {
        let flag = self.budget.flag().map(|f| format!(" ({f})")).unwrap_or_default();
        match self.budget {
            Budget::Steps => format!("more than {} {}{flag}", human(self.limit), self.model.step_unit()),
            Budget::WallTime => format!("more than {} s of computing{flag}", human(self.limit)),
            Budget::Memory => {
                format!("more than {} {}, the most whose impacts a run keeps in memory", human(self.limit), self.model.kept_unit())
            }
        }
    }
}

impl ModelError {
    /// The run so far, when a budget stopped it.
    pub fn partial(&self) -> Option<&Run> {
        match self {
            ModelError::OverBudget(b) => Some(&b.partial),
            _ => None,
        }
    }
}
