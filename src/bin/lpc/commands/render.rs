//! `lpc render`: numbered PNG frames of a run in 3D, off-screen (the `render` feature).

use std::path::PathBuf;

use anyhow::Context;

use lpc_damper::model::RunOptions;
use lpc_damper::output::write_run_dir;
use lpc_damper::scene::{Overrides, Scene};
use lpc_damper::Model;

use crate::args::{invalid, load_scene, parse_size, BudgetArgs, ModelArgs};
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
    settings: ModelArgs,
    #[command(flatten)]
    budget: BudgetArgs,
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
    let s = load_scene(&a.scene, a.settings.overrides(None, None))?;
    // Frames fall on samples: the run is sampled at a step dividing the frame interval.
    let (sample_dt, per_frame) = lpc_damper::run::frame_sampling(a.fps, s.sample_dt);
    let timing = Overrides { horizon: a.horizon, sample_dt: Some(sample_dt), ..Overrides::default() };
    let s = timing.apply(s, &a.scene.display().to_string())?;
    let run = crate::watch::watched(a.model, &s, RunOptions::limited(a.budget.limits(&a.scene)?))?;
    write_run_dir(&run, &a.out).with_context(|| format!("writing outputs to {}", a.out.display()))?;
    render_run(&s, &run, &a, per_frame)?;
    Ok(ExitStatus::Success)
}

#[cfg(feature = "render")]
fn render_run(s: &Scene, run: &lpc_damper::run::Run, a: &Args, per_frame: usize) -> Result<()> {
    let options = lpc_damper::render::RenderOptions { out: a.out.clone(), size: a.size, samples_per_frame: per_frame };
    let runtime = quiet_wayland_probe();
    let frames = lpc_damper::render::render_frames(s, run, &options);
    if let Some(dir) = runtime {
        let _ = std::fs::remove_dir(dir);
    }
    let frames = frames?;
    let gif = a.out.join("animation.gif");
    lpc_damper::render::animation::write_gif(&frames, a.fps, &gif)?;
    println!(
        "{} frames ({}x{}, {} fps, sample step {:e} s) and {} in {}",
        frames.len(),
        a.size.0,
        a.size.1,
        a.fps,
        run.sample_dt,
        gif.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        a.out.display()
    );
    Ok(())
}

/// Mesa's Vulkan driver probes for a Wayland display even off-screen, and libwayland prints
/// "XDG_RUNTIME_DIR is invalid or not set" on every run where the variable is unset (CI,
/// containers, ssh sessions). An empty private runtime directory makes the probe fail
/// quietly; nothing else reads it. Returns the directory to remove afterwards.
#[cfg(feature = "render")]
fn quiet_wayland_probe() -> Option<PathBuf> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| !d.is_empty()) {
        return None;
    }
    let dir = std::env::temp_dir().join(format!("lpc-runtime-{}", std::process::id()));
    std::fs::create_dir_all(&dir).ok()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700)).ok()?;
    }
    // Edition 2021: setting a variable is safe; it happens before the renderer starts its
    // threads, while only the main thread (and rayon's idle pool) exists.
    std::env::set_var("XDG_RUNTIME_DIR", &dir);
    Some(dir)
}

#[cfg(not(feature = "render"))]
fn render_run(_: &Scene, _: &lpc_damper::run::Run, _: &Args, _: usize) -> Result<()> {
    unreachable!("`lpc render` refuses before running when the renderer is not built")
}
