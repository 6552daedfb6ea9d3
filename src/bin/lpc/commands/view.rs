//! `lpc view`: a run replayed in an interactive 3D window (the `render` feature and a display).

use std::path::PathBuf;

use lpc_damper::model::RunOptions;
use lpc_damper::Model;

use crate::args::{load_scene, BudgetArgs, ModelArgs};
use crate::exit::{CommandError, ExitStatus, Result};

#[derive(clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Model that runs the scene (the window replays its trajectory).
    #[arg(long, default_value = "rapier")]
    model: Model,
    /// Simulated time, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    #[command(flatten)]
    settings: ModelArgs,
    #[command(flatten)]
    budget: BudgetArgs,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    if !cfg!(feature = "render") {
        return Err(CommandError::failure(anyhow::anyhow!(
            "this lpc was built without a renderer: build it with `cargo run --release --features render -- view ...`"
        )));
    }
    // The window is an X11 one; without a display winit cannot start (and would panic).
    if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        return Err(CommandError::failure(anyhow::anyhow!(
            "no display: `lpc view` needs an X11 display (DISPLAY is not set); `lpc render` draws frames off-screen"
        )));
    }
    let s = load_scene(&a.scene, a.settings.overrides(a.horizon, None))?;
    let run = crate::watch::watched(a.model, &s, RunOptions::limited(a.budget.limits(&a.scene)?))?;
    #[cfg(feature = "render")]
    lpc_damper::render::window::view(&s, run);
    #[cfg(not(feature = "render"))]
    drop(run);
    Ok(ExitStatus::Success)
}
