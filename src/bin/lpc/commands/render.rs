//! `lpc render`: numbered PNG frames of a run in 3D, off-screen (the `render` feature).

use std::path::PathBuf;

use anyhow::Context;

use lpc_damper::output::write_run_dir;
use lpc_damper::scene::{Overrides, Scene};
use lpc_damper::Model;

use crate::args::{invalid, load_scene, parse_size, RapierArgs};
use crate::exit::{CommandError, ExitStatus, Result};

#[derive(clap::Args)]
pub struct Args {
    /// Scene file.
    scene: PathBuf,
    /// Directory for frame_00000.png, ... and the run's series.csv, impacts.csv, summary.json.
    #[arg(long)]
    out: PathBuf,
    /// Frames per simulated second.
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
    /// Frame size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Simulated time to render, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    /// Model that runs the scene.
    #[arg(long, default_value = "reference")]
    model: Model,
    #[command(flatten)]
    rapier: RapierArgs,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    if !cfg!(feature = "render") {
        return Err(CommandError::failure(anyhow::anyhow!(
            "this lpc was built without a renderer: build it with `cargo run --release --features render -- render ...`"
        )));
    }
    if !(a.fps.is_finite() && a.fps > 0.0 && a.fps <= 10_000.0) {
        return Err(invalid(&a.scene, "--fps", format!("must lie in (0, 10000] (got {})", a.fps)).into());
    }
    let s = load_scene(&a.scene, a.rapier.overrides(None, None))?;
    // Frames fall on samples: the run is sampled at a step dividing the frame interval.
    let (sample_dt, per_frame) = lpc_damper::run::frame_sampling(a.fps, s.sample_dt);
    let timing = Overrides { horizon: a.horizon, sample_dt: Some(sample_dt), ..Overrides::default() };
    let s = timing.apply(s, &a.scene.display().to_string())?;
    let run = a.model.simulate(&s)?;
    write_run_dir(&run, &a.out).with_context(|| format!("writing outputs to {}", a.out.display()))?;
    render_run(&s, &run, &a, per_frame)?;
    Ok(ExitStatus::Success)
}

#[cfg(feature = "render")]
fn render_run(s: &Scene, run: &lpc_damper::run::Run, a: &Args, per_frame: usize) -> Result<()> {
    let options = lpc_damper::render::RenderOptions { out: a.out.clone(), size: a.size, samples_per_frame: per_frame };
    let frames = lpc_damper::render::render_frames(s, run, &options)?;
    println!("{} frames ({}x{}, {} fps, sample step {:e} s) in {}", frames.len(), a.size.0, a.size.1, a.fps, run.sample_dt, a.out.display());
    Ok(())
}

#[cfg(not(feature = "render"))]
fn render_run(_: &Scene, _: &lpc_damper::run::Run, _: &Args, _: usize) -> Result<()> {
    unreachable!("`lpc render` refuses before running when the renderer is not built")
}
