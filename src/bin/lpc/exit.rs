//! How a command ends, and the process exit code each ending maps to (in one place).
//!
//! The exit class of an error is decided where the error is made, by its type: a
//! [`SceneError`] (a scene file or a flag that cannot exist) is bad input; a study's error
//! that wraps one says so in its own variant; everything else is a failed run. Nothing
//! searches an error chain for a type that a transparent wrapper may hide.

use std::process::ExitCode;

use lpc_damper::model::ModelError;
use lpc_damper::output::figures::FigureError;
use lpc_damper::scene::SceneError;
use lpc_damper::studies::StudyError;

/// How a command ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExitStatus {
    /// Everything asked for was done (exit 0).
    Success,
    /// A run failed: a model stalled or refused the scene, an output could not be written, a
    /// stressed run or a frequency failed (exit 1).
    Failure,
    /// Bad input: a scene or a flag that cannot exist, a missing file (exit 2).
    BadInput,
    /// `lpc check` found a value outside its tolerance (exit 3).
    Regression,
}

impl From<ExitStatus> for ExitCode {
    fn from(status: ExitStatus) -> ExitCode {
        ExitCode::from(match status {
            ExitStatus::Success => 0,
            ExitStatus::Failure => 1,
            ExitStatus::BadInput => 2,
            ExitStatus::Regression => 3,
        })
    }
}

/// A command that could not finish: what to tell the user, and its exit class.
#[derive(Debug)]
pub struct CommandError {
    /// [`ExitStatus::Failure`] or [`ExitStatus::BadInput`].
    pub status: ExitStatus,
    /// The message, with its context.
    pub error: anyhow::Error,
}

/// What every command returns.
pub type Result<T> = std::result::Result<T, CommandError>;

impl CommandError {
    /// A failed run (exit 1).
    pub fn failure(error: impl Into<anyhow::Error>) -> Self {
        CommandError { status: ExitStatus::Failure, error: error.into() }
    }
    /// Bad input (exit 2).
    pub fn bad_input(error: impl Into<anyhow::Error>) -> Self {
        CommandError { status: ExitStatus::BadInput, error: error.into() }
    }
}

impl From<SceneError> for CommandError {
    fn from(e: SceneError) -> Self {
        CommandError::bad_input(e)
    }
}

impl From<StudyError> for CommandError {
    fn from(e: StudyError) -> Self {
        match e {
            StudyError::Scene(s) => CommandError::bad_input(s),
            other => CommandError::failure(other),
        }
    }
}

/// Errors that only ever mean a failed run.
macro_rules! failures {
    ($($t:ty),* $(,)?) => {$(
        impl From<$t> for CommandError {
            fn from(e: $t) -> Self {
                CommandError::failure(e)
            }
        }
    )*};
}

failures!(anyhow::Error, ModelError, FigureError, std::io::Error, serde_json::Error, csv::Error, std::string::FromUtf8Error);

#[cfg(feature = "render")]
failures!(lpc_damper::render::RenderError);

impl<W: std::fmt::Debug + Send + Sync + 'static> From<csv::IntoInnerError<W>> for CommandError {
    fn from(e: csv::IntoInnerError<W>) -> Self {
        CommandError::failure(anyhow::anyhow!("{e}"))
    }
}
