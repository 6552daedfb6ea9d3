//! `lpc`: the command-line tool. A thin layer over the library: parse arguments, load a scene,
//! run models, print or write outputs.
//!
//! Exit status: 0 success; 1 a run failed (a model stalled or refused the scene, an output
//! could not be written); 2 bad input (a scene or a flag that cannot exist, a missing file).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use lpc_damper::chain::{run_chain, KerRow};
use lpc_damper::compare::{errors, Errors};
use lpc_damper::output::{text_summary, write_atomic, write_run_dir, RunSummary};
use lpc_damper::scene::{self, Scene, SceneError};
use lpc_damper::Model;

#[derive(Parser)]
#[command(name = "lpc", version, about = "Simulate the Linear Particle Chain impact damper (Gharib & Ghani 2013)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run one model on a scene and print a summary (or write series, impacts and summary).
    Run(RunArgs),
    /// Run every value of a scene's [sweep] table, in parallel.
    Sweep(SweepArgs),
    /// Frequency response: steady amplitude of xs against forcing frequency, with and without
    /// the damper (needs a [forcing] table, or --kind and --amplitude).
    Frf(FrfArgs),
    /// Find the design (arrangement and parameters) with the shortest settling time or the
    /// lowest resonant amplitude inside a given container length.
    Optimize(OptimizeArgs),
    /// The chain experiment (Fig. 5): kinetic energy ratio against the number of large balls.
    Chain(ChainArgs),
    /// Run several models on one scene and report each one's errors against the reference.
    Compare(CompareArgs),
    /// Run time against error for every model and setting; marks the Pareto front.
    Bench(BenchArgs),
    /// Random valid scenes through every model, checked for instability; failures shrunk.
    Stress(StressArgs),
    /// Headless regression runs: every scene with every model against tests/golden/.
    Check(CheckArgs),
    /// The contact model's stability map: step size x impact speed, with and without CCD.
    Stability(StabilityArgs),
    /// The paper's figures (PNG and SVG) from a scene, a run directory or a compare directory.
    Plot(PlotArgs),
    /// Numbered PNG frames of a run in 3D, off-screen (needs `--features render`).
    Render(RenderArgs),
    /// A run in an interactive 3D window (needs `--features render` and a display).
    View(ViewArgs),
}

#[derive(clap::Args)]
struct ViewArgs {
    /// Scene file.
    scene: PathBuf,
    /// Model that runs the scene (the window replays its trajectory).
    #[arg(long, default_value = "rapier")]
    model: Model,
    /// Simulated time, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    #[command(flatten)]
    rapier: RapierArgs,
}

#[derive(clap::Args)]
struct RenderArgs {
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

#[derive(clap::Args)]
struct PlotArgs {
    /// A scene file (damper: Figs. 8-12; [sweep]: Figs. 13-16; [chain]: Fig. 5), a directory
    /// written by `lpc run --out` (its series), or one written by `lpc compare --out` (overlay).
    input: PathBuf,
    /// Directory for the figures.
    #[arg(long)]
    out: PathBuf,
    /// Model that runs a scene.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Figure size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1000x640", value_parser = parse_size)]
    size: (u32, u32),
    #[command(flatten)]
    rapier: RapierArgs,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not a size WIDTHxHEIGHT between 100x100 and 8000x8000");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if !(100..=8000).contains(&w) || !(100..=8000).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

#[derive(clap::Args)]
struct StabilityArgs {
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// Directory of scene files.
    #[arg(default_value = "scenes")]
    dir: PathBuf,
    /// Directory of golden files.
    #[arg(long, default_value = "tests/golden")]
    golden: PathBuf,
    /// Models, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "reference,rapier,compliant")]
    models: Vec<Model>,
    /// Rewrite the golden files from this run.
    #[arg(long)]
    update: bool,
    /// Print every compared value, not only the failures.
    #[arg(long)]
    verbose: bool,
}

#[derive(clap::Args)]
struct StressArgs {
    /// Scenes per model.
    #[arg(long, default_value_t = 200)]
    count: u64,
    /// First seed (scene k uses seed + k).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Models, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "reference,rapier")]
    models: Vec<Model>,
    /// Longest horizon drawn, s.
    #[arg(long, default_value_t = 100.0)]
    max_horizon: f64,
    /// Drive every scene by a harmonic force or base motion (from far below to far above the
    /// frame's resonance, from barely impacting to violent).
    #[arg(long)]
    forced: bool,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Write each failure's minimal scene into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
enum TableFormat {
    Text,
    Json,
    Csv,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scene files (default: the paper's damper scenes).
    scenes: Vec<PathBuf>,
    /// Models, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "reference,rapier,compliant")]
    models: Vec<Model>,
    /// Rapier steppings, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "fixed,aligned")]
    stepping: Vec<lpc_damper::rapier::Stepping>,
    /// Rapier steps (longest steps when aligned), s, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.0001,0.0002,0.0005,0.001,0.002")]
    dt: Vec<f64>,
    /// Rapier solver iterations, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "4")]
    solver_iterations: Vec<u32>,
    /// Compliant model error tolerances, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1e-9")]
    tolerance: Vec<f64>,
    /// Runs per setting; the median time is reported.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Simulated time, s (overrides the scenes').
    #[arg(long)]
    horizon: Option<f64>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = TableFormat::Text)]
    format: TableFormat,
    /// Write bench.csv, bench.json and error_vs_cost.svg into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
enum Format {
    Text,
    Json,
}

#[derive(clap::Args)]
struct RunArgs {
    /// Scene file (TOML), e.g. scenes/lpc-lsl.toml.
    scene: PathBuf,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Simulated time, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    /// Output sampling step, s (default 1 ms).
    #[arg(long)]
    sample_dt: Option<f64>,
    #[command(flatten)]
    rapier: RapierArgs,
    /// Write series.csv, impacts.csv and summary.json into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

#[derive(clap::Args)]
struct SweepArgs {
    /// Scene file with a [sweep] table.
    scene: PathBuf,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Simulated time, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Also write sweep.json (and, for a grid, the design map sweep-map.png/.svg) into this
    /// directory.
    #[arg(long)]
    out: Option<PathBuf>,
    /// First axis instead of the file's [sweep]: `PARAM=V1,V2,...` or `PARAM=A..B:N`
    /// (lengths may be `0.5Rr`).
    #[arg(long)]
    x: Option<String>,
    /// Second axis (makes a grid): same syntax as --x.
    #[arg(long)]
    y: Option<String>,
    /// Metric of the design map (one of settling_time, energy_remaining, peak_contact_force,
    /// peak_displacement, peak_acceleration, rms_displacement, impact_count).
    #[arg(long, default_value = "settling_time")]
    metric: String,
    #[command(flatten)]
    rapier: RapierArgs,
}

#[derive(clap::Args)]
struct FrfArgs {
    /// Scene file.
    scene: PathBuf,
    /// Frequency range `A..B` in Hz.
    #[arg(long)]
    freq: String,
    /// Number of frequencies, evenly spaced over the range.
    #[arg(long, default_value_t = 21)]
    steps: usize,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Forcing kind, when the scene has no [forcing] table (or to override it).
    #[arg(long, value_enum)]
    kind: Option<ForcingKindArg>,
    /// Forcing amplitude (N for a force, m for base motion), when the scene has no [forcing]
    /// table (or to override it).
    #[arg(long)]
    amplitude: Option<f64>,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Write frf.json, frf.csv and the plot (frf.png, frf.svg) into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    rapier: RapierArgs,
}

#[derive(clap::Args)]
struct OptimizeArgs {
    /// Scene file (its [balls] table is the starting design).
    scene: PathBuf,
    /// Inner container length (m, or `<k> Rr`); default: the scene's.
    #[arg(long)]
    container_length: Option<String>,
    /// A design parameter and its range: `PARAM=A..B:N` or `PARAM=V1,V2,...` (repeatable).
    #[arg(long = "vary")]
    vary: Vec<String>,
    /// Ball arrangements to try, comma-separated (default: the scene's).
    #[arg(long)]
    arrangements: Option<String>,
    /// What to minimise.
    #[arg(long, value_enum, default_value_t = ObjectiveArg::SettlingTime)]
    objective: ObjectiveArg,
    /// Frequency range `A..B` in Hz for the resonant amplitude.
    #[arg(long)]
    freq: Option<String>,
    /// Frequencies over that range.
    #[arg(long, default_value_t = 9)]
    steps: usize,
    /// Refinements around the best grid point.
    #[arg(long, default_value_t = 2)]
    refinements: u32,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Designs listed in the text output.
    #[arg(long, default_value_t = 10)]
    top: usize,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

#[derive(Clone, Copy, ValueEnum)]
enum ObjectiveArg {
    SettlingTime,
    ResonantAmplitude,
}

#[derive(Clone, Copy, ValueEnum)]
enum ForcingKindArg {
    Force,
    Base,
}

/// Settings of the Rapier model that every command accepts.
#[derive(clap::Args, Clone, Copy)]
struct RapierArgs {
    /// Rapier model: `aligned` (steps end at contacts) or `fixed` steps.
    #[arg(long)]
    stepping: Option<lpc_damper::rapier::Stepping>,
    /// Rapier model: physics step (the longest one when aligned), s.
    #[arg(long)]
    dt: Option<f64>,
    /// Rapier model: solver iterations per step (overrides the scene's).
    #[arg(long)]
    solver_iterations: Option<u32>,
    /// Rapier model: turn on Rapier's swept CCD for the balls.
    #[arg(long)]
    ccd: bool,
}

impl RapierArgs {
    fn apply(self, scene: &mut Scene, path: &Path) -> Result<(), SceneError> {
        let invalid = |field: &str, rule: String| SceneError::Invalid { file: path.display().to_string(), field: field.into(), rule };
        if let Some(s) = self.stepping {
            scene.rapier.stepping = Some(s);
        }
        if let Some(dt) = self.dt {
            if !(dt.is_finite() && dt > 0.0 && dt <= 0.1) {
                return Err(invalid("--dt", format!("must be a step in (0, 0.1] s (got {dt})")));
            }
            scene.rapier.dt = Some(dt);
        }
        if let Some(it) = self.solver_iterations {
            if !(1..=1000).contains(&it) {
                return Err(invalid("--solver-iterations", format!("must lie in 1..=1000 (got {it})")));
            }
            scene.rapier.solver_iterations = Some(it);
        }
        if self.ccd {
            scene.rapier.ccd = Some(true);
        }
        Ok(())
    }
}

#[derive(clap::Args)]
struct CompareArgs {
    /// Scene file.
    scene: PathBuf,
    /// Models to compare with the reference, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "reference,rapier,compliant")]
    models: Vec<Model>,
    /// Simulated time, s (overrides the scene's).
    #[arg(long)]
    horizon: Option<f64>,
    #[command(flatten)]
    rapier: RapierArgs,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Write each model's series.csv, impacts.csv and summary.json into DIR/MODEL/.
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(clap::Args)]
struct ChainArgs {
    /// Chain scene file (default: scenes/chain-ker.toml).
    scene: Option<PathBuf>,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    #[command(flatten)]
    rapier: RapierArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(a) => cmd_run(a),
        Command::Sweep(a) => cmd_sweep(a),
        Command::Frf(a) => cmd_frf(a),
        Command::Optimize(a) => cmd_optimize(a),
        Command::Chain(a) => cmd_chain(a),
        Command::Compare(a) => cmd_compare(a),
        Command::Bench(a) => cmd_bench(a),
        Command::Stress(a) => cmd_stress(a),
        Command::Stability(a) => cmd_stability(a),
        Command::Plot(a) => cmd_plot(a),
        Command::Render(a) => cmd_render(a),
        Command::View(a) => cmd_view(a),
        Command::Check(a) => return cmd_check(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            if e.chain().any(|c| c.is::<SceneError>()) {
                ExitCode::from(2)
            } else {
                ExitCode::from(1)
            }
        }
    }
}

/// Applies `--horizon` and `--sample-dt`, with the scene's own rules.
fn override_run(scene: &mut Scene, path: &Path, horizon: Option<f64>, sample_dt: Option<f64>) -> Result<(), SceneError> {
    let invalid = |field: &str, rule: String| SceneError::Invalid { file: path.display().to_string(), field: field.into(), rule };
    if let Some(h) = horizon {
        if !(h.is_finite() && h > 0.0) {
            return Err(invalid("--horizon", format!("must be a positive number of seconds (got {h})")));
        }
        scene.horizon = h;
    }
    if let Some(dt) = sample_dt {
        scene.sample_dt = dt;
    }
    let field = if sample_dt.is_some() { "--sample-dt" } else { "run.sample_dt" };
    scene::check_sample_dt(scene.horizon, scene.sample_dt).map_err(|rule| invalid(field, rule))
}

fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    println!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}

fn cmd_run(a: RunArgs) -> Result<()> {
    let mut scene = scene::load_scene(&a.scene)?;
    override_run(&mut scene, &a.scene, a.horizon, a.sample_dt)?;
    a.rapier.apply(&mut scene, &a.scene)?;
    let run = a.model.simulate(&scene)?;
    let summary = RunSummary::of(&run);
    if let Some(dir) = &a.out {
        write_run_dir(&run, dir).with_context(|| format!("writing outputs to {}", dir.display()))?;
    }
    match a.format {
        Format::Json => print_json(&summary)?,
        Format::Text => {
            print!("{}", text_summary(&summary));
            if let Some(dir) = &a.out {
                println!("wrote series.csv, impacts.csv, summary.json to {}", dir.display());
            }
        }
    }
    Ok(())
}

/// A progress bar on a terminal when there is enough work to wait for; hidden otherwise.
fn progress_bar(len: usize, label: &str) -> ProgressBar {
    let bar = if len > 4 { ProgressBar::new(len as u64) } else { ProgressBar::hidden() };
    bar.set_style(ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({elapsed})").expect("valid template"));
    bar.set_message(label.to_string());
    bar
}

fn cmd_sweep(a: SweepArgs) -> Result<()> {
    let loaded = scene::load(&a.scene)?;
    let invalid = |field: &str, rule: String| SceneError::Invalid { file: a.scene.display().to_string(), field: field.into(), rule };
    if !lpc_damper::sweep::MAP_METRICS.contains(&a.metric.as_str()) {
        return Err(invalid("--metric", format!("`{}` is not one of {}", a.metric, lpc_damper::sweep::MAP_METRICS.join(", "))).into());
    }
    let mut axes = match &a.x {
        Some(x) => vec![lpc_damper::sweep::parse_axis(x).map_err(|rule| invalid("--x", rule))?],
        None if a.y.is_some() => return Err(invalid("--y", "needs --x".into()).into()),
        None => lpc_damper::sweep::file_axes(&loaded)?,
    };
    if let Some(y) = &a.y {
        axes.truncate(1);
        axes.push(lpc_damper::sweep::parse_axis(y).map_err(|rule| invalid("--y", rule))?);
    }
    if loaded.scene.is_none() {
        return Err(invalid("frame", "is missing: a sweep needs a damper scene".into()).into());
    }
    let mut grid = lpc_damper::sweep::grid_scenes(&loaded, &axes)?;
    for g in &mut grid {
        override_run(&mut g.scene, &a.scene, a.horizon, None)?;
        a.rapier.apply(&mut g.scene, &a.scene)?;
    }
    let parameters: Vec<String> = axes.iter().map(|x| x.parameter.clone()).collect();
    let parameter = parameters.join(" x ");
    let bar = progress_bar(grid.len(), "sweep");
    let start = std::time::Instant::now();
    let points = lpc_damper::sweep::run_grid(&parameters, &grid, a.model, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let elapsed = start.elapsed().as_secs_f64();
    if let Some(dir) = &a.out {
        write_atomic(&dir.join("sweep.json"), &serde_json::to_vec_pretty(&points)?)
            .with_context(|| format!("writing {}", dir.display()))?;
        if axes.len() == 2 {
            let (nx, ny) = (axes[0].values.len(), axes[1].values.len());
            let z = (0..ny)
                .map(|r| (0..nx).map(|c| lpc_damper::sweep::metric_value(&points[r * nx + c].summary, &a.metric)).collect())
                .collect();
            let map = lpc_damper::output::figures::HeatMap {
                name: "sweep-map".into(),
                title: format!("{}: {} ({})", loaded.scene.as_ref().map_or("", |s| s.name.as_str()), a.metric, a.model.name()),
                x: (axis_title(&axes[0]), axes[0].values.iter().map(|v| v.raw()).collect()),
                y: (axis_title(&axes[1]), axes[1].values.iter().map(|v| v.raw()).collect()),
                z,
                z_desc: a.metric.clone(),
            };
            lpc_damper::output::figures::write_heat_map(&map, dir, (900, 640))?;
        }
    }
    match a.format {
        Format::Json => print_json(&points)?,
        Format::Text => {
            println!(
                "sweep of `{parameter}` ({}, {} runs in {:.3} s: {:.1} scene-runs per second)",
                a.model.name(),
                points.len(),
                elapsed,
                points.len() as f64 / elapsed
            );
            let y_head = parameters.get(1).map_or(String::new(), |p| format!("{p:>12} "));
            println!(
                "{:>12} {y_head}{:>8} {:>12} {:>12} {:>10} {:>10} {:>9}",
                parameters[0], "impacts", "peak xs mm", "peak a m/s2", "rms xs mm", "settle s", "E left %"
            );
            for p in &points {
                let m = &p.summary.metrics;
                let y = p.value_y.map_or(String::new(), |v| format!("{v:>12} "));
                println!(
                    "{:>12} {y}{:>8} {:>12.4} {:>12.4} {:>10.4} {:>10} {:>9.3}",
                    p.value,
                    p.summary.impact_count,
                    m.peak_displacement * 1e3,
                    m.peak_acceleration,
                    m.rms_displacement * 1e3,
                    m.settling_time.map_or("-".into(), |t| format!("{t:.3}")),
                    m.energy_remaining.unwrap_or(f64::NAN) * 100.0
                );
            }
            if let (Some(dir), 2) = (&a.out, axes.len()) {
                println!("wrote sweep.json, sweep-map.png, sweep-map.svg to {}", dir.display());
            }
        }
    }
    Ok(())
}

/// An axis's parameter, with `(Rr)` when its values are multiples of the reference radius.
fn axis_title(axis: &lpc_damper::sweep::Axis) -> String {
    let rr = axis.values.iter().any(|v| matches!(v, scene::Length::Rr(_)));
    if rr {
        format!("{} (Rr)", axis.parameter)
    } else {
        axis.parameter.clone()
    }
}

fn parse_range(text: &str, path: &Path, field: &str) -> Result<(f64, f64), SceneError> {
    let invalid = |rule: String| SceneError::Invalid { file: path.display().to_string(), field: field.into(), rule };
    let (a, b) = text.split_once("..").ok_or_else(|| invalid(format!("`{text}` is not a range: write `A..B`")))?;
    let num = |s: &str| s.trim().parse::<f64>().map_err(|_| invalid(format!("`{s}` in `{text}` is not a number")));
    let (a, b) = (num(a)?, num(b)?);
    if !(a.is_finite() && b.is_finite() && a > 0.0 && b >= a) {
        return Err(invalid(format!("`{text}` must be positive and increasing")));
    }
    Ok((a, b))
}

fn cmd_frf(a: FrfArgs) -> Result<()> {
    let mut scene = scene::load_scene(&a.scene)?;
    a.rapier.apply(&mut scene, &a.scene)?;
    let (from, to) = parse_range(&a.freq, &a.scene, "--freq")?;
    let invalid = |field: &str, rule: String| SceneError::Invalid { file: a.scene.display().to_string(), field: field.into(), rule };
    if a.steps == 0 || a.steps > 10_000 {
        return Err(invalid("--steps", format!("must lie in 1..=10000 (got {})", a.steps)).into());
    }
    if a.kind.is_some() || a.amplitude.is_some() {
        let g = scene.forcing.get_or_insert(scene::Forcing { kind: scene::ForcingKind::Force, amplitude: 0.0, frequency: from });
        if let Some(k) = a.kind {
            g.kind = match k {
                ForcingKindArg::Force => scene::ForcingKind::Force,
                ForcingKindArg::Base => scene::ForcingKind::Base,
            };
        }
        if let Some(x) = a.amplitude {
            if !(x.is_finite() && x > 0.0) {
                return Err(invalid("--amplitude", format!("must be a positive number (got {x})")).into());
            }
            g.amplitude = x;
        }
    }
    let Some(g) = scene.forcing else {
        return Err(invalid("forcing", "is missing: give the scene a [forcing] table, or --kind and --amplitude".into()).into());
    };
    if g.amplitude == 0.0 {
        return Err(invalid("forcing.amplitude", "is 0: give --amplitude".into()).into());
    }
    if let Some(f) = scene.frame {
        // An undamped frame driven at resonance has no steady state (scene validation's rule).
        let w0 = (f.stiffness / f.mass).sqrt() / (2.0 * std::f64::consts::PI);
        if f.damping == 0.0 && from <= w0 && w0 <= to {
            return Err(invalid("--freq", format!("{from}..{to} Hz contains the undamped frame's resonance {w0:.6} Hz, where no steady state exists")).into());
        }
    }
    let freqs = lpc_damper::frf::frequencies(from, to, a.steps);
    let bar = progress_bar(2 * freqs.len(), "frf");
    let start = std::time::Instant::now();
    let points = lpc_damper::frf::frf(&scene, &freqs, a.model, &|| bar.inc(1));
    bar.finish_and_clear();
    let elapsed = start.elapsed().as_secs_f64();
    if let Some(dir) = &a.out {
        write_atomic(&dir.join("frf.json"), &serde_json::to_vec_pretty(&points)?)
            .with_context(|| format!("writing {}", dir.display()))?;
        let mut w = csv::Writer::from_writer(Vec::new());
        for p in &points {
            w.serialize(p)?;
        }
        write_atomic(&dir.join("frf.csv"), &w.into_inner()?).with_context(|| format!("writing {}", dir.display()))?;
        let fig = lpc_damper::output::figures::frf_chart(&points, &scene.name, a.model.name());
        lpc_damper::output::figures::write(&fig, dir, (900, 560))?;
    }
    match a.format {
        Format::Json => print_json(&points)?,
        Format::Text => {
            println!(
                "frequency response of {} ({}, {:?} forcing, amplitude {}; {} runs in {:.2} s)",
                scene.name,
                a.model.name(),
                g.kind,
                g.amplitude,
                2 * points.len(),
                elapsed
            );
            println!(
                "{:>10} {:>14} {:>14} {:>8} {:>16} {:>22}",
                "f Hz", "amp mm", "no damper mm", "ratio", "impacts/period", "steady (with/without)"
            );
            let mm = |x: Option<f64>| x.map_or("failed".to_string(), |x| format!("{:.4}", x * 1e3));
            for p in &points {
                let ratio = match (p.amplitude, p.amplitude_no_damper) {
                    (Some(a), Some(b)) => format!("{:.3}", a / b),
                    _ => "-".into(),
                };
                println!(
                    "{:>10.4} {:>14} {:>14} {:>8} {:>16} {:>22}",
                    p.frequency,
                    mm(p.amplitude),
                    mm(p.amplitude_no_damper),
                    ratio,
                    p.impacts_per_period.map_or("-".into(), |x| format!("{x:.2}")),
                    format!("{}/{}", if p.steady { "yes" } else { "no" }, if p.steady_no_damper { "yes" } else { "no" })
                );
            }
            for p in points.iter().filter(|p| p.error.is_some()) {
                println!("{} Hz failed: {}", p.frequency, p.error.as_deref().unwrap_or_default());
            }
            if let Some(dir) = &a.out {
                println!("wrote frf.json, frf.csv, frf.png, frf.svg to {}", dir.display());
            }
        }
    }
    let failed = points.iter().filter(|p| p.error.is_some()).count();
    if failed > 0 {
        return Err(anyhow::anyhow!("{failed} of {} frequencies failed (see above)", points.len()));
    }
    Ok(())
}

fn cmd_optimize(a: OptimizeArgs) -> Result<()> {
    use lpc_damper::optimize::{optimize, Objective};
    let loaded = scene::load(&a.scene)?;
    let invalid = |field: &str, rule: String| SceneError::Invalid { file: a.scene.display().to_string(), field: field.into(), rule };
    let Some(base) = loaded.scene.clone() else {
        return Err(invalid("frame", "is missing: a design needs a damper scene".into()).into());
    };
    let length = match &a.container_length {
        Some(text) => match text.trim().parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => scene::Length::Metres(x),
            _ => scene::Length::try_from_text(text)
                .ok_or_else(|| invalid("--container-length", format!("`{text}` is not a positive length (m or `<k> Rr`)")))?,
        },
        None => scene::Length::Metres(base.container.map_or(0.0, |c| c.length)),
    };
    let axes = a
        .vary
        .iter()
        .map(|v| lpc_damper::sweep::parse_axis(v).map_err(|rule| invalid("--vary", rule)))
        .collect::<Result<Vec<_>, _>>()?;
    let arrangements: Vec<String> = match &a.arrangements {
        Some(list) => list.split(',').map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect(),
        None => match &loaded.file.balls.as_ref().map(|b| b.arrangement.clone()) {
            Some(scene::Arrangement::Letters(l)) => vec![l.clone()],
            _ => return Err(invalid("--arrangements", "is needed: the scene lists its balls explicitly".into()).into()),
        },
    };
    if arrangements.is_empty() {
        return Err(invalid("--arrangements", "is empty".into()).into());
    }
    let objective = match a.objective {
        ObjectiveArg::SettlingTime => Objective::SettlingTime,
        ObjectiveArg::ResonantAmplitude => {
            let text = a.freq.as_deref().ok_or_else(|| invalid("--freq", "is needed for the resonant amplitude".into()))?;
            let (from, to) = parse_range(text, &a.scene, "--freq")?;
            Objective::ResonantAmplitude { from, to, steps: a.steps.max(1) }
        }
    };
    let bar = progress_bar(usize::MAX >> 1, "designs");
    bar.set_style(ProgressStyle::with_template("{msg} {pos} ({elapsed})").expect("valid template"));
    let start = std::time::Instant::now();
    let search = optimize(&loaded, &axes, &arrangements, length, objective, a.model, a.refinements, &|| bar.inc(1))
        .map_err(|e| match e {
            lpc_damper::optimize::OptimizeError::Scene(s) => anyhow::Error::from(s),
            lpc_damper::optimize::OptimizeError::Model(m) => anyhow::Error::from(m),
        })?;
    bar.finish_and_clear();
    match a.format {
        Format::Json => print_json(&search)?,
        Format::Text => {
            let unit = match objective {
                Objective::SettlingTime => "settling time s",
                Objective::ResonantAmplitude { .. } => "resonant amplitude mm",
            };
            let scale = if matches!(objective, Objective::SettlingTime) { 1.0 } else { 1e3 };
            println!(
                "{} designs evaluated in {:.2} s ({} infeasible: balls do not fit {length}); container length fixed",
                search.ranking.len() + search.infeasible,
                start.elapsed().as_secs_f64(),
                search.infeasible
            );
            println!("{:>12} {:>12} {:>22}  parameters", "arrangement", "clearance mm", unit);
            for d in search.ranking.iter().take(a.top) {
                let params = d.values.iter().map(|(p, v)| format!("{p}={v}")).collect::<Vec<_>>().join(" ");
                println!(
                    "{:>12} {:>12.3} {:>22}  {params}",
                    d.arrangement,
                    d.clearance * 1e3,
                    d.objective.map_or("not settled".into(), |x| format!("{:.4}", x * scale))
                );
            }
            match &search.best {
                Some(b) => println!("best: {} with {}", b.arrangement, b.values.iter().map(|(p, v)| format!("{p}={v}")).collect::<Vec<_>>().join(" ")),
                None => println!("no feasible design settled"),
            }
        }
    }
    Ok(())
}

fn cmd_chain(a: ChainArgs) -> Result<()> {
    let path = a.scene.unwrap_or_else(|| PathBuf::from("scenes/chain-ker.toml"));
    let loaded = scene::load(&path)?;
    let cases = loaded.chain.ok_or_else(|| SceneError::Invalid {
        file: path.display().to_string(),
        field: "chain".into(),
        rule: "is missing: `lpc chain` needs a scene file with a [chain] table".into(),
    })?;
    let mut cases = cases;
    for c in &mut cases {
        a.rapier.apply(&mut c.scene, &path)?;
    }
    let rows: Vec<KerRow> = run_chain(&cases, a.model)?;
    match a.format {
        Format::Json => print_json(&rows)?,
        Format::Text => {
            println!("kinetic energy ratio ({}): KE of all balls after / KE of the incident ball", a.model.name());
            println!("{:>7} {:>7} {:>10}", "large", "small", "KER");
            for r in &rows {
                println!("{:>7} {:>7} {:>10.4}", r.large, r.small, r.ker);
            }
        }
    }
    Ok(())
}

/// One model's entry in `lpc compare`'s JSON.
#[derive(serde::Serialize)]
struct ModelComparison {
    summary: RunSummary,
    errors: Errors,
}

/// `lpc compare`'s JSON.
#[derive(serde::Serialize)]
struct Comparison {
    scene: String,
    reference: RunSummary,
    models: std::collections::BTreeMap<String, ModelComparison>,
}

fn cmd_compare(a: CompareArgs) -> Result<()> {
    let mut scene = scene::load_scene(&a.scene)?;
    override_run(&mut scene, &a.scene, a.horizon, None)?;
    a.rapier.apply(&mut scene, &a.scene)?;
    let reference = Model::Reference.simulate(&scene)?;
    let mut models = std::collections::BTreeMap::new();
    let mut runs = vec![];
    for &m in a.models.iter().filter(|m| **m != Model::Reference) {
        let run = m.simulate(&scene)?;
        models.insert(m.name().to_string(), ModelComparison { summary: RunSummary::of(&run), errors: errors(&run, &reference) });
        runs.push(run);
    }
    if let Some(dir) = &a.out {
        for run in std::iter::once(&reference).chain(&runs) {
            let d = dir.join(&run.model);
            write_run_dir(run, &d).with_context(|| format!("writing outputs to {}", d.display()))?;
        }
    }
    let comparison = Comparison { scene: scene.name.clone(), reference: RunSummary::of(&reference), models };
    match a.format {
        Format::Json => print_json(&comparison)?,
        Format::Text => {
            let st = lpc_damper::rapier::settings(&scene);
            println!(
                "scene {} (rapier: {} steps, dt {} s, {} solver iterations)",
                scene.name,
                st.stepping.name(),
                st.dt,
                st.solver_iterations
            );
            println!(
                "{:>10} {:>10} {:>10} {:>12} {:>12} {:>12} {:>12} {:>14}",
                "model", "wall ms", "x realtime", "rms xs mm", "early xs mm", "settle d s", "loss d %E0", "impacts (d)"
            );
            let row = |name: &str, s: &RunSummary, e: Option<&Errors>| {
                let e = e.copied();
                println!(
                    "{:>10} {:>10.3} {:>10.0} {:>12} {:>12} {:>12} {:>12} {:>14}",
                    name,
                    s.wall_time_s * 1e3,
                    s.horizon / s.wall_time_s,
                    e.map_or("-".into(), |e| format!("{:.4}", e.rms_xs * 1e3)),
                    e.map_or("-".into(), |e| format!("{:.4}", e.max_xs_early * 1e3)),
                    e.map_or("-".into(), |e| e.settling_time_diff.map_or("n/a".into(), |d| format!("{d:+.3}"))),
                    e.map_or("-".into(), |e| format!("{:+.3}", e.impact_loss_diff * 100.0)),
                    match e {
                        Some(e) => format!("{} ({:+})", s.impact_count, e.impact_count_diff),
                        None => s.impact_count.to_string(),
                    }
                );
            };
            row("reference", &comparison.reference, None);
            for (name, m) in &comparison.models {
                row(name, &m.summary, Some(&m.errors));
            }
            if let Some(dir) = &a.out {
                println!("wrote every model's series to {}/MODEL/", dir.display());
            }
        }
    }
    Ok(())
}

fn cmd_bench(a: BenchArgs) -> Result<()> {
    let paths = if a.scenes.is_empty() {
        ["conventional", "lpc-lsl", "lpc-lslsl", "chain-lll"].iter().map(|n| PathBuf::from(format!("scenes/{n}.toml"))).collect()
    } else {
        a.scenes.clone()
    };
    for &dt in &a.dt {
        if !(dt.is_finite() && dt > 0.0 && dt <= 0.1) {
            return Err(SceneError::Invalid { file: "(command line)".into(), field: "--dt".into(), rule: format!("must be a step in (0, 0.1] s (got {dt})") }.into());
        }
    }
    if let Some(&it) = a.solver_iterations.iter().find(|&&it| !(1..=1000).contains(&it)) {
        return Err(SceneError::Invalid {
            file: "(command line)".into(),
            field: "--solver-iterations".into(),
            rule: format!("must lie in 1..=1000 (got {it})"),
        }
        .into());
    }
    let plan = lpc_damper::bench::Plan {
        models: a.models.clone(),
        steppings: a.stepping.clone(),
        dts: a.dt.clone(),
        solver_iterations: a.solver_iterations.clone(),
        compliant_tolerances: a.tolerance.clone(),
        repeat: a.repeat,
    };
    let per_scene = a.models.iter().map(|m| match m {
        Model::Reference => 1,
        Model::Rapier => plan.steppings.len() * plan.dts.len() * plan.solver_iterations.len(),
        Model::Compliant => plan.compliant_tolerances.len(),
    }).sum::<usize>();
    let bar = progress_bar(per_scene * paths.len(), "bench");
    let mut rows = Vec::new();
    for p in &paths {
        let mut scene = scene::load_scene(p)?;
        override_run(&mut scene, p, a.horizon, None)?;
        rows.extend(lpc_damper::bench::bench_scene(&scene, &plan, &|| bar.inc(1))?);
    }
    bar.finish_and_clear();
    let csv_bytes = bench_csv(&rows)?;
    if let Some(dir) = &a.out {
        write_atomic(&dir.join("bench.csv"), &csv_bytes)?;
        write_atomic(&dir.join("bench.json"), &serde_json::to_vec_pretty(&rows)?)?;
        let svg = dir.join("error_vs_cost.svg");
        lpc_damper::output::plot::error_vs_cost(&rows, &svg).map_err(|e| anyhow::anyhow!("drawing {}: {e}", svg.display()))?;
    }
    match a.format {
        TableFormat::Json => print_json(&rows)?,
        TableFormat::Csv => print!("{}", String::from_utf8(csv_bytes)?),
        TableFormat::Text => {
            println!(
                "{:>14} {:>9} {:>8} {:>8} {:>4} {:>12} {:>10} {:>9} {:>11} {:>10} {:>9} {:>7}",
                "scene", "model", "stepping", "dt", "it", "s per sim s", "steps/s", "rms mm", "early mm", "settle s", "loss %", "pareto"
            );
            for r in &rows {
                let e = &r.errors;
                println!(
                    "{:>14} {:>9} {:>8} {:>8} {:>4} {:>12.5} {:>10.0} {:>9.4} {:>11.5} {:>10} {:>9.3} {:>7}",
                    r.scene,
                    r.model,
                    r.settings.stepping,
                    // The compliant model has no step to set: its column shows the tolerance.
                    r.settings.dt.map(|d| format!("{d}")).or(r.settings.tolerance.map(|t| format!("tol {t:e}"))).unwrap_or("-".into()),
                    r.settings.solver_iterations.map_or("-".into(), |i| i.to_string()),
                    r.wall_s_per_sim_s,
                    r.steps_per_sim_s,
                    e.rms_xs * 1e3,
                    e.max_xs_early * 1e3,
                    e.settling_time_diff.map_or("n/a".into(), |d| format!("{d:+.3}")),
                    e.impact_loss_diff * 100.0,
                    if r.pareto { "*" } else { "" }
                );
            }
            if let Some(dir) = &a.out {
                println!("wrote bench.csv, bench.json, error_vs_cost.svg to {}", dir.display());
            }
        }
    }
    Ok(())
}

fn bench_csv(rows: &[lpc_damper::bench::BenchRow]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "scene", "model", "stepping", "dt", "solver_iterations", "wall_s_per_sim_s", "steps_per_sim_s", "rms_xs",
        "max_xs_early", "settling_time_diff", "impact_loss_diff", "impact_count_diff", "pareto", "tolerance",
    ])?;
    let opt = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
    for r in rows {
        let e = &r.errors;
        w.write_record([
            r.scene.clone(),
            r.model.to_string(),
            r.settings.stepping.to_string(),
            opt(r.settings.dt),
            r.settings.solver_iterations.map_or(String::new(), |i| i.to_string()),
            r.wall_s_per_sim_s.to_string(),
            r.steps_per_sim_s.to_string(),
            e.rms_xs.to_string(),
            e.max_xs_early.to_string(),
            opt(e.settling_time_diff),
            e.impact_loss_diff.to_string(),
            e.impact_count_diff.to_string(),
            r.pareto.to_string(),
            opt(r.settings.tolerance),
        ])?;
    }
    Ok(w.into_inner()?)
}

fn cmd_stress(a: StressArgs) -> Result<()> {
    let mut outcomes = Vec::new();
    let start = std::time::Instant::now();
    for &model in &a.models {
        let bar = progress_bar(a.count as usize, &format!("stress {}", model.name()));
        outcomes.extend(lpc_damper::stress::stress(model, a.seed, a.count, a.max_horizon, a.forced, &|| bar.inc(1)));
        bar.finish_and_clear();
    }
    let failures: Vec<_> = outcomes.iter().filter(|o| o.failure.is_some()).collect();
    if let Some(dir) = &a.out {
        for o in &failures {
            let path = dir.join(format!("stress-{}-{}.toml", o.model, o.seed));
            write_atomic(&path, o.minimal_scene.as_deref().unwrap_or("").as_bytes())?;
        }
    }
    match a.format {
        Format::Json => print_json(&outcomes)?,
        Format::Text => {
            for o in &failures {
                let f = o.failure.as_ref().expect("failure");
                println!("FAIL {} seed {}: {} ({})", o.model, o.seed, f.check, f.detail);
                if let Some(m) = &o.minimal_scene {
                    println!("minimal scene:\n{m}");
                }
            }
            for &model in &a.models {
                let total = outcomes.iter().filter(|o| o.model == model.name()).count();
                let failed = failures.iter().filter(|o| o.model == model.name()).count();
                let refused = outcomes.iter().filter(|o| o.model == model.name() && o.refused.is_some()).count();
                let unstable = outcomes.iter().filter(|o| o.model == model.name() && o.refused_during_run).count();
                println!(
                    "{}: {} passed ({} of them refused with a reason, {} of those during the run), {} failed",
                    model.name(),
                    total - failed,
                    refused,
                    unstable,
                    failed
                );
            }
            println!("({:.1} s)", start.elapsed().as_secs_f64());
        }
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(anyhow::anyhow!("{} of {} stressed runs failed", failures.len(), outcomes.len()))
    }
}

fn cmd_view(a: ViewArgs) -> Result<()> {
    if !cfg!(feature = "render") {
        return Err(anyhow::anyhow!("this lpc was built without a renderer: build it with `cargo run --release --features render -- view ...`"));
    }
    // The window is an X11 one; without a display winit cannot start (and would panic).
    if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        return Err(anyhow::anyhow!("no display: `lpc view` needs an X11 display (DISPLAY is not set); `lpc render` draws frames off-screen"));
    }
    let mut s = scene::load_scene(&a.scene)?;
    a.rapier.apply(&mut s, &a.scene)?;
    override_run(&mut s, &a.scene, a.horizon, None)?;
    let run = a.model.simulate(&s)?;
    #[cfg(feature = "render")]
    lpc_damper::render::window::view(&s, run);
    #[cfg(not(feature = "render"))]
    drop(run);
    Ok(())
}

fn cmd_render(a: RenderArgs) -> Result<()> {
    if !cfg!(feature = "render") {
        return Err(anyhow::anyhow!(
            "this lpc was built without a renderer: build it with `cargo run --release --features render -- render ...`"
        ));
    }
    if !(a.fps.is_finite() && a.fps > 0.0 && a.fps <= 10_000.0) {
        return Err(SceneError::Invalid { file: a.scene.display().to_string(), field: "--fps".into(), rule: format!("must lie in (0, 10000] (got {})", a.fps) }.into());
    }
    let mut s = scene::load_scene(&a.scene)?;
    a.rapier.apply(&mut s, &a.scene)?;
    // Frames fall on samples: the run is sampled at a step dividing the frame interval.
    let (sample_dt, per_frame) = lpc_damper::run::frame_sampling(a.fps, s.sample_dt);
    override_run(&mut s, &a.scene, a.horizon, Some(sample_dt))?;
    let run = a.model.simulate(&s)?;
    write_run_dir(&run, &a.out).with_context(|| format!("writing outputs to {}", a.out.display()))?;
    render_run(&s, &run, &a, per_frame)
}

#[cfg(feature = "render")]
fn render_run(s: &Scene, run: &lpc_damper::run::Run, a: &RenderArgs, per_frame: usize) -> Result<()> {
    let options = lpc_damper::render::RenderOptions { out: a.out.clone(), size: a.size, samples_per_frame: per_frame };
    let frames = lpc_damper::render::render_frames(s, run, &options)?;
    println!("{} frames ({}x{}, {} fps, sample step {:e} s) in {}", frames.len(), a.size.0, a.size.1, a.fps, run.sample_dt, a.out.display());
    Ok(())
}

#[cfg(not(feature = "render"))]
fn render_run(_: &Scene, _: &lpc_damper::run::Run, _: &RenderArgs, _: usize) -> Result<()> {
    unreachable!("cmd_render refuses before running when the renderer is not built")
}

fn cmd_plot(a: PlotArgs) -> Result<()> {
    use lpc_damper::output::figures::{self, Figure};
    let mut figs: Vec<Figure> = vec![];
    if a.input.is_dir() {
        let series = |dir: &Path| dir.join("series.csv");
        let name_of = |dir: &Path, key: &str| -> Option<String> {
            let text = std::fs::read(dir.join("summary.json")).ok()?;
            let v: serde_json::Value = serde_json::from_slice(&text).ok()?;
            v.get(key)?.as_str().map(str::to_string)
        };
        if series(&a.input).is_file() {
            let s = figures::read_series_csv(&series(&a.input))?;
            let mut run = lpc_damper::run::Run::empty(
                &name_of(&a.input, "scene").unwrap_or_else(|| "run".into()),
                &name_of(&a.input, "model").unwrap_or_else(|| "model".into()),
            );
            run.series = s;
            figs.extend(figures::time_histories(&run, None));
            figs.push(figures::ball_positions(&run, None));
        } else {
            let mut models = vec![];
            let mut entries: Vec<PathBuf> =
                std::fs::read_dir(&a.input)?.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| series(p).is_file()).collect();
            entries.sort();
            for dir in entries {
                let name = dir.file_name().map_or("model".into(), |n| n.to_string_lossy().into_owned());
                models.push((name, figures::read_series_csv(&series(&dir))?));
            }
            if models.is_empty() {
                return Err(SceneError::Invalid {
                    file: a.input.display().to_string(),
                    field: "input".into(),
                    rule: "holds no series.csv (expected a directory of `lpc run --out` or `lpc compare --out`)".into(),
                }
                .into());
            }
            let scene_name = name_of(&a.input.join(&models[0].0), "scene").unwrap_or_default();
            figs.push(figures::overlay(&models, &scene_name));
        }
    } else {
        let loaded = scene::load(&a.input)?;
        if let Some(mut cases) = loaded.chain.clone() {
            for c in &mut cases {
                a.rapier.apply(&mut c.scene, &a.input)?;
            }
            figs.push(figures::ker_chart(&run_chain(&cases, a.model)?, a.model.name()));
        } else if loaded.file.sweep.is_some() {
            use rayon::prelude::*;
            let mut scenes = lpc_damper::sweep::sweep_scenes(&loaded)?;
            for (_, s) in &mut scenes {
                a.rapier.apply(s, &a.input)?;
            }
            let parameter = loaded.file.sweep.as_ref().map_or(String::new(), |s| s.parameter.clone());
            let values: Vec<String> = loaded.file.sweep.as_ref().map_or(vec![], |s| s.values.iter().map(|v| v.to_string()).collect());
            let runs = scenes
                .par_iter()
                .zip(values)
                .map(|((_, s), label)| Ok((label, a.model.simulate(s)?)))
                .collect::<Result<Vec<_>, lpc_damper::model::ModelError>>()?;
            figs.push(figures::sweep_curves(&parameter, &runs));
        } else {
            let mut s = loaded.scene.clone().expect("a scene file without [chain] has [frame]");
            a.rapier.apply(&mut s, &a.input)?;
            let run = a.model.simulate(&s)?;
            let bare = lpc_damper::reference::simulate(&s.without_damper())?;
            figs.extend(figures::time_histories(&run, (!s.balls.is_empty()).then_some(&bare)));
            if !s.balls.is_empty() {
                figs.push(figures::ball_positions(&run, s.container.map(|c| c.length)));
            }
        }
    }
    for f in &figs {
        for p in figures::write(f, &a.out, a.size)? {
            println!("{}", p.display());
        }
    }
    Ok(())
}

fn cmd_stability(a: StabilityArgs) -> Result<()> {
    use lpc_damper::stability::{self, Case, CONFIGS, DTS, SPEEDS};
    let cells = stability::map();
    match a.format {
        Format::Json => print_json(&cells)?,
        Format::Text => {
            println!("outcome per impact speed (rows, m/s) and step (columns, s); energy error vs the reference in %");
            for case in Case::ALL {
                for config in CONFIGS {
                    println!("\n{} / {}", case.name(), config.name);
                    print!("{:>8}", "u \\ dt");
                    for dt in DTS {
                        print!(" {:>22}", format!("{dt:e}"));
                    }
                    println!();
                    for speed in SPEEDS {
                        print!("{speed:>8}");
                        for dt in DTS {
                            let c = cells
                                .iter()
                                .find(|c| c.case == case && c.config == config.name && c.dt == dt && c.speed == speed)
                                .expect("cell");
                            print!(" {:>22}", format!("{} {:+.1}", c.outcome, 100.0 * c.energy_error));
                        }
                        println!();
                    }
                }
            }
        }
    }
    Ok(())
}

/// Exit status of `lpc check` when a value left its tolerance.
const EXIT_REGRESSION: u8 = 3;

fn cmd_check(a: CheckArgs) -> ExitCode {
    use lpc_damper::check;
    let run = || -> Result<Vec<check::Row>> {
        let now = check::current(&a.dir, &a.models)?;
        let mut rows = Vec::new();
        for g in &now {
            if a.update {
                check::write_golden(&a.golden, g)?;
            }
            let golden = if a.update { Some(g.clone()) } else { check::read_golden(&a.golden, g)? };
            rows.extend(check::compare(g, golden.as_ref()));
        }
        Ok(rows)
    };
    let rows = match run() {
        Ok(rows) => rows,
        Err(e) => {
            eprintln!("error: {e:#}");
            return if e.chain().any(|c| c.is::<SceneError>()) { ExitCode::from(2) } else { ExitCode::from(1) };
        }
    };
    let fmt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.6e}"));
    println!("{:<34} {:>9} {:<18} {:>14} {:>14} {:>10} {:>6}", "case", "model", "metric", "golden", "now", "tolerance", "");
    for r in rows.iter().filter(|r| a.verbose || !r.ok) {
        println!(
            "{:<34} {:>9} {:<18} {:>14} {:>14} {:>10.1e} {:>6}",
            r.case,
            r.model,
            r.metric,
            fmt(r.golden),
            fmt(r.now),
            r.tolerance,
            if r.ok { "ok" } else { "FAIL" }
        );
    }
    let failed = rows.iter().filter(|r| !r.ok).count();
    println!("{} passed, {} failed", rows.len() - failed, failed);
    if a.update {
        println!("golden files rewritten in {}", a.golden.display());
    }
    if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(EXIT_REGRESSION)
    }
}
