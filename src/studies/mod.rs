//! Studies on top of runs: each asks the models many questions and answers with a table.
//! They share one error type; none knows how a model works inside.

pub mod bench;
pub mod chain;
pub mod check;
pub mod compare;
pub mod ensemble;
pub mod frf;
pub mod optimize;
pub mod stability;
pub mod stress;
pub mod sweep;

use crate::model::ModelError;
use crate::scene::SceneError;

/// Why a study could not run (a single run's failure inside a study is part of its answer,
/// where the study reports one per row).
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A scene, or a parameter the study derived from one, is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A model failed.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A file the study reads or writes (a golden file) could not be.
    #[error("{path}: {message}")]
    Io {
        /// Path.
        path: String,
        /// Why.
        message: String,
    },
}
